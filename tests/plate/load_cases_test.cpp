// Several load cases in one model (SensorOptions::load_cases; docs/model.md, "Several load
// cases"): one factorization per configuration serves every case, so each case of a shared model
// must give what a model of that case alone gives, on the clamp-only fast path (certified,
// residual-checked and pivoting) and with continuous unknowns (series and direct), and what the
// full solve of that case gives; and the precompute must be shared, not repeated per case.
#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "combabc/core/error.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "plate_test_support.hpp"

namespace combabc::plate {
namespace {

// Each case of the shared model against its own model, relative to that case's largest |w|: the
// same algebra on the same pieces, except where another case's load makes a section unique that
// the case's own model shares with a twin (whose output rows were interpolated at positions equal
// to round-off): round-off at most (measured: at most 5e-15, about half of the outputs
// bit-identical).
constexpr double kSameModelTol = 1e-12;
// Against the full sparse solve, relative to each case's maximum (as the single-case tests).
constexpr double kFullSolveTol = 1e-9;

using testing::RandomClamps;

// All fixed, all free, then random configurations.
std::vector<std::vector<std::uint8_t>> Configurations(int count, int clamps, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<std::uint8_t>> all;
  for (int i = 0; i < testing::Repetitions(count); ++i) {
    all.push_back(RandomClamps(rng, clamps));
    if (i < 2) std::fill(all.back().begin(), all.back().end(), i == 0 ? 1 : 0);
  }
  return all;
}

// Three cases: the default load at 0.45 m (on a section boundary, with 12 sections a side also a
// group boundary: its 1 cm patch loads the two sections beside it) with the default outputs; a
// point load inside a section and off the centre line, scanned along its own line
// (y = width / 4) at its own positions; and a load inside a section at 0.70 m with the first
// case's outputs (two cases on one output set, each with its own offsets).
std::vector<LoadCase> ThreeCases() {
  LoadCase first;
  LoadCase inside;
  inside.load_x = 0.3712;
  inside.load_y_fraction = 0.25;
  inside.load_patch_length = 0.0;
  inside.load_force = 0.03;
  inside.output_positions = {0.0, 0.05, 0.1, 0.2, 0.3, 0.3712, 0.4, 0.52, 0.66, 0.9};
  inside.output_y_fraction = 0.25;
  LoadCase second_load;
  second_load.load_x = 0.70;
  second_load.load_force = 0.05;
  return {first, inside, second_load};
}

// The shared options' model of case c alone.
SensorOptions CaseAlone(SensorOptions o, std::size_t c) {
  o.load_cases = {o.load_cases[c]};
  return o;
}

// Coarse meshes and 12 sections a side (4 groups: 3 rows in the block elimination) keep the test
// light (it also runs under the sanitizers): the identities are algebraic, so the mesh does not
// matter to them. The default theory (RZT, quadratic elements).
SensorOptions CoarseRzt() {
  SensorOptions o;
  o.clamps_per_edge = 12;
  o.elements_per_section = 2;
  o.elements_across_width = 2;
  o.load_cases = ThreeCases();
  return o;
}

// Kirchhoff, the theory the continuous-unknowns tests are tuned to (sensor_variation_test.cpp).
SensorOptions CoarseKirchhoff() {
  SensorOptions o = CoarseRzt();
  o.theory = PlateTheory::kKirchhoff;
  o.elements_per_section = 4;
  return o;
}

// Worst difference of each case's complex outputs between the shared model (`shared`, all cases)
// and its own model (`alone`, case c's), relative to the case's largest |w|; counts the outputs
// whose bits agree.
struct Agreement {
  double worst = 0.0;
  int identical = 0;
  int total = 0;
  void Add(std::span<const std::complex<double>> shared,
           std::span<const std::complex<double>> alone) {
    ASSERT_EQ(shared.size(), alone.size());
    double diff = 0.0;
    double scale = 0.0;
    for (std::size_t k = 0; k < shared.size(); ++k) {
      diff = std::max(diff, std::abs(shared[k] - alone[k]));
      scale = std::max(scale, std::abs(alone[k]));
      identical += std::bit_cast<std::uint64_t>(shared[k].real()) ==
                       std::bit_cast<std::uint64_t>(alone[k].real()) &&
                   std::bit_cast<std::uint64_t>(shared[k].imag()) ==
                       std::bit_cast<std::uint64_t>(alone[k].imag());
      ++total;
    }
    ASSERT_GT(scale, 0.0);
    worst = std::max(worst, diff / scale);
  }
  void Expect(const char* what) const {
    std::printf("%s: worst %.2e, %d of %d outputs bit-identical\n", what, worst, identical, total);
    EXPECT_LT(worst, kSameModelTol) << what;
  }
};

// Each case of the shared model of `o` against its own model over `count` configurations; with a
// variation, through the continuous unknowns (an empty one: the clamp-only fast path).
void ExpectCasesEqualTheirOwnModels(const SensorOptions& o,
                                    const SensorVariation& variation,
                                    int count,
                                    const char* what) {
  const SensorModel shared(o);
  ASSERT_EQ(shared.num_load_cases(), static_cast<int>(o.load_cases.size()));
  std::vector<std::unique_ptr<SensorModel>> alone;
  for (std::size_t c = 0; c < o.load_cases.size(); ++c) {
    alone.push_back(std::make_unique<SensorModel>(CaseAlone(o, c)));
  }
  std::vector<std::complex<double>> w(shared.num_outputs());
  Agreement agreement;
  for (const auto& clamps : Configurations(count, shared.num_clamps(), 7)) {
    shared.ComplexProfile(clamps, variation, w);
    for (std::size_t c = 0; c < alone.size(); ++c) {
      std::vector<std::complex<double>> own(alone[c]->num_outputs());
      alone[c]->ComplexProfile(clamps, variation, own);
      agreement.Add(std::span(w).subspan(o.OutputOffset(c), own.size()), own);
    }
  }
  agreement.Expect(what);
}

TEST(PlateLoadCases, EachCaseEqualsItsOwnModel) {
  const SensorVariation none;
  SensorOptions o = CoarseRzt();
  ASSERT_TRUE(SensorModel(o).fast_path_certified());
  ExpectCasesEqualTheirOwnModels(o, none, 4, "rzt, certified");
  // Above a resonance: not certified, every case's solution is residual-checked.
  o = CoarseKirchhoff();
  o.frequency_hz = 120.0;
  ASSERT_FALSE(SensorModel(o).fast_path_certified());
  ExpectCasesEqualTheirOwnModels(o, none, 4, "kirchhoff at 120 Hz, residual-checked");
  // The pivoting LU of the condensed system (the fallback) for every case: in
  // CasesOnTheSameSectionsGiveTheirOwnModelsBits.
  // Groups of 2 sections (8 per edge), other supports.
  o = CoarseKirchhoff();
  o.clamps_per_edge = 8;
  o.fixed_support = Support::kSimplySupported;
  o.short_edge_start = Support::kClamped;
  ExpectCasesEqualTheirOwnModels(o, none, 4, "kirchhoff, 8 sections a side, simply supported");
}

TEST(PlateLoadCases, EachCaseEqualsItsOwnModelWithContinuousUnknowns) {
  SensorVariation series;  // |mu| / lambda_1 small: the power series
  series.foundation_stiffness = 3.0e4;
  series.stiffness_scale = 0.8;
  series.loss_factor = 0.2;
  SensorVariation direct;  // a laminate 500 times softer: every state condensed directly
  direct.stiffness_scale = 2e-3;
  const SensorOptions o = CoarseKirchhoff();
  {
    const SensorModel model(o);
    for (const int terms : model.VariationSeriesTerms(series)) ASSERT_GT(terms, 0);
    for (const int terms : model.VariationSeriesTerms(direct)) ASSERT_EQ(terms, -1);
  }
  ExpectCasesEqualTheirOwnModels(o, series, 4, "kirchhoff, continuous unknowns, series");
  ExpectCasesEqualTheirOwnModels(o, direct, 4, "kirchhoff, continuous unknowns, direct");
  ExpectCasesEqualTheirOwnModels(CoarseRzt(), series, 3, "rzt, continuous unknowns, series");
  SensorOptions resonant = o;
  resonant.frequency_hz = 120.0;
  ExpectCasesEqualTheirOwnModels(resonant, series, 3, "kirchhoff at 120 Hz, continuous unknowns");
}

// Cases whose loads touch the same sections make no section or group unique that their own
// models share, so the pieces agree bit for bit, and so must the outputs: the shared
// factorization, the back substitution of several cases side by side and the output recovery
// run each case's column through exactly the operations of a single case. Three cases: the
// default, a weaker load scanned along its own line, the load moved across the width.
TEST(PlateLoadCases, CasesOnTheSameSectionsGiveTheirOwnModelsBits) {
  SensorVariation series;
  series.foundation_stiffness = 3.0e4;
  series.stiffness_scale = 0.8;
  const auto expect_bits = [&](SensorOptions o, const char* what) {
    o.load_cases = {LoadCase{}, LoadCase{}, LoadCase{}};
    o.load_cases[1].load_force = 0.02;
    o.load_cases[1].output_y_fraction = 0.25;
    o.load_cases[2].load_y_fraction = 0.3;
    const SensorModel shared(o);
    std::vector<std::unique_ptr<SensorModel>> alone;
    for (std::size_t c = 0; c < o.load_cases.size(); ++c) {
      alone.push_back(std::make_unique<SensorModel>(CaseAlone(o, c)));
    }
    std::vector<std::complex<double>> w(shared.num_outputs());
    std::vector<std::complex<double>> own(alone[0]->num_outputs());
    Agreement agreement;
    for (const auto& clamps : Configurations(3, shared.num_clamps(), 5)) {
      for (const SensorVariation& v : {SensorVariation{}, series}) {
        shared.ComplexProfile(clamps, v, w);
        for (std::size_t c = 0; c < alone.size(); ++c) {
          alone[c]->ComplexProfile(clamps, v, own);
          agreement.Add(std::span(w).subspan(o.OutputOffset(c), own.size()), own);
        }
      }
    }
    agreement.Expect(what);
    EXPECT_EQ(agreement.identical, agreement.total) << what;
  };
  expect_bits(CoarseRzt(), "rzt, certified");
  SensorOptions o = CoarseKirchhoff();
  o.frequency_hz = 120.0;
  expect_bits(o, "kirchhoff at 120 Hz, residual-checked");
  o = CoarseRzt();
  o.always_pivot = true;
  expect_bits(o, "rzt, pivoting LU");
}

// Each case of the shared model against the full sparse solve of that case (the reference path:
// ProfileFullSolve solves case after case), normalised per case; with continuous unknowns against
// the full solve of the model built with the variation's values.
TEST(PlateLoadCases, EachCaseEqualsItsFullSolve) {
  for (const SensorOptions& o : {CoarseRzt(), CoarseKirchhoff()}) {
    SCOPED_TRACE(ToString(o.theory));
    const SensorModel model(o);
    SensorVariation variation;
    variation.foundation_stiffness = 2.0e4;
    variation.stiffness_scale = 1.3;
    const SensorModel varied(ApplyVariation(o, variation));
    std::vector<double> fast(model.num_outputs());
    std::vector<double> full(model.num_outputs());
    std::vector<double> fast_varied(model.num_outputs());
    std::vector<double> full_varied(model.num_outputs());
    double worst = 0.0;
    double worst_varied = 0.0;
    for (const auto& clamps : Configurations(5, model.num_clamps(), 11)) {
      model.Profile(clamps, fast);
      model.ProfileFullSolve(clamps, full);
      model.Profile(clamps, variation, fast_varied);
      varied.ProfileFullSolve(clamps, full_varied);
      for (std::size_t c = 0; c < o.load_cases.size(); ++c) {
        const std::size_t begin = o.OutputOffset(c);
        const std::size_t end = o.OutputOffset(c + 1);
        // Each case is normalised by its own maximum.
        EXPECT_DOUBLE_EQ(*std::max_element(fast.begin() + begin, fast.begin() + end), 1.0);
        for (std::size_t k = begin; k < end; ++k) {
          worst = std::max(worst, std::abs(fast[k] - full[k]));
          worst_varied = std::max(worst_varied, std::abs(fast_varied[k] - full_varied[k]));
        }
      }
    }
    std::printf("%s: worst against the full solve %.2e, with continuous unknowns %.2e\n",
                ToString(o.theory),
                worst,
                worst_varied);
    EXPECT_LT(worst, kFullSolveTol);
    EXPECT_LT(worst_varied, kFullSolveTol);
  }
}

// A floating plate (no foundation, free short edges, 0 Hz) with every clamp free is singular: the
// shared solve refuses it for its cases as the single-case one does, and solves the cantilever
// that one fixed clamp makes of it.
TEST(PlateLoadCases, SingularConfigurationsAreRefused) {
  SensorOptions o = CoarseRzt();
  o.foundation_stiffness = 0.0;
  o.frequency_hz = 0.0;
  const SensorModel model(o);
  std::vector<std::uint8_t> clamps(model.num_clamps(), 0);
  std::vector<double> out(model.num_outputs());
  EXPECT_THROW(model.Profile(clamps, out), SingularSystem);
  clamps[0] = 1;
  std::vector<double> full(model.num_outputs());
  model.Profile(clamps, out);
  model.ProfileFullSolve(clamps, full);
  double worst = 0.0;
  for (std::size_t k = 0; k < out.size(); ++k) worst = std::max(worst, std::abs(out[k] - full[k]));
  EXPECT_LT(worst, kFullSolveTol);
}

// A second case is named by its index in the message and in the error's field.
TEST(PlateLoadCases, InvalidCasesNameTheirIndex) {
  SensorOptions o = CoarseRzt();
  o.load_cases[1].load_x = 1.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "SensorOptions::load_cases[1].load_x = 1; must lie on the plate, in [0, 0.9] m");
  try {
    const SensorModel model(o);
    FAIL() << "expected combabc::Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    EXPECT_EQ(e.field(), "SensorOptions::load_cases[1].load_x");
  }
  o = CoarseRzt();
  o.load_cases[2].output_y_fraction = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "SensorOptions::load_cases[2].output_y_fraction = 1.5; must be in [0, 1]");
  o.load_cases.clear();
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "SensorOptions::load_cases.size() = 0; must be in [1, 1000]");
}

// The cases share the precompute: a second case on the same outputs adds its load columns, its
// offsets and the group pieces its load makes distinct, not a second copy of every piece (one
// condensation per case kept 2 x; measured 1.03 x here).
TEST(PlateLoadCases, CasesShareThePrecomputedPieces) {
  SensorOptions o = CoarseRzt();
  o.load_cases = {ThreeCases()[0], ThreeCases()[2]};
  const SensorModel two(o);
  const SensorModel one(CaseAlone(o, 0));
  const auto ratio =
      static_cast<double>(two.PrecomputedBytes()) / static_cast<double>(one.PrecomputedBytes());
  std::printf("pieces of two cases on one output set / of one case: %.3f\n", ratio);
  EXPECT_LT(ratio, 1.25);
}

}  // namespace
}  // namespace combabc::plate
