// The sensor simulator with continuous unknowns (SensorVariation): the per-call condensation
// against the full sparse solve of a model built with the same values (ApplyVariation), on both
// of its section paths (series and direct), its agreement with the clamp-only fast path, and its
// validation and batch behaviour.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "combabc/core/error.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "plate/fast_path/continuous_condensation.hpp"
#include "plate_test_support.hpp"

namespace combabc::plate {
namespace {

// Relative to the profile's maximum: the requirement (1e-9; measured: 1e-15 to 1e-10, the largest
// for an undamped floating strip near a resonance, where the clamp-only fast path and the full
// solve differ as much).
constexpr double kVariationTol = 1e-9;
// Where the system is well conditioned the agreement is at round-off, and a check this tight
// catches a truncated series: summing half the terms the series needs moves these differences to
// 7e-11 - 1e-10 (checked), still inside kVariationTol.
constexpr double kRoundOffTol = 1e-12;

using testing::MaxRelativeDifference;
using testing::RandomClamps;

SensorVariation Variation(std::optional<double> k_f,
                          std::optional<double> s,
                          std::optional<double> eta) {
  SensorVariation v;
  v.foundation_stiffness = k_f;
  v.stiffness_scale = s;
  v.loss_factor = eta;
  return v;
}

std::string Describe(const SensorVariation& v) {
  const auto f = [](const std::optional<double>& x) {
    return x ? std::to_string(*x) : std::string("unset");
  };
  return "k_f " + f(v.foundation_stiffness) + ", s " + f(v.stiffness_scale) + ", eta " +
         f(v.loss_factor);
}

// The variation path of `model` against the full solve of the model built with the variation's
// values, over `configurations` configurations (all fixed, all free, then random). Returns the
// worst relative difference.
double WorstAgainstFullSolve(const SensorModel& model,
                             const SensorVariation& variation,
                             int configurations,
                             std::uint64_t seed) {
  const SensorModel reference(ApplyVariation(model.options(), variation));
  std::mt19937_64 rng(seed);
  std::vector<double> fast(model.num_outputs());
  std::vector<double> full(model.num_outputs());
  double worst = 0.0;
  for (int i = 0; i < testing::Repetitions(configurations); ++i) {
    std::vector<std::uint8_t> clamps = RandomClamps(rng, model.num_clamps());
    if (i == 0) std::fill(clamps.begin(), clamps.end(), 1);
    if (i == 1) std::fill(clamps.begin(), clamps.end(), 0);
    model.Profile(clamps, variation, fast);
    reference.ProfileFullSolve(clamps, full);
    worst = std::max(worst, MaxRelativeDifference(fast, full));
  }
  return worst;
}

// A coarse mesh keeps the unit test light (it also runs under ASan); the default mesh is checked
// by the `slow` test. The identity is algebraic, so the mesh does not matter to it.
// Kirchhoff, the theory these tests were written for (a proportionally damped laminate; the
// series bounds below are tuned to its stiffness); FSDT and RZT at their default element order
// have their own tests (EqualsFullSolveFsdt, EqualsFullSolveRzt).
SensorOptions CoarseOptions() {
  SensorOptions o;
  o.theory = PlateTheory::kKirchhoff;
  o.elements_per_section = 4;
  o.elements_across_width = 2;
  return o;
}

void ExpectVariationsEqualFullSolve(const SensorOptions& options,
                                    const std::vector<SensorVariation>& variations,
                                    int configurations,
                                    double tol = kVariationTol) {
  const SensorModel model(options);
  double worst = 0.0;
  for (std::size_t v = 0; v < variations.size(); ++v) {
    const double d = WorstAgainstFullSolve(model, variations[v], configurations, 10 + v);
    const auto terms = model.VariationSeriesTerms(variations[v]);
    std::printf("%-50s terms %3d %3d %3d %3d: worst %.2e\n",
                Describe(variations[v]).c_str(),
                terms[0],
                terms[1],
                terms[2],
                terms[3],
                d);
    EXPECT_LT(d, tol) << Describe(variations[v]);
    worst = std::max(worst, d);
  }
  std::printf("worst relative difference over all variations: %.2e\n", worst);
}

// Values a calibration would try: each unknown alone and together, the loss factor set and left
// to the layers (whose own factors differ: 0.10, 0.15, 0.10, so K_imag is not eta K_real).
std::vector<SensorVariation> TypicalVariations() {
  return {Variation(2.0e4, std::nullopt, std::nullopt),
          Variation(std::nullopt, 0.5, std::nullopt),
          Variation(std::nullopt, std::nullopt, 0.3),
          Variation(1.5e5, 2.0, std::nullopt),
          Variation(8.0e3, 0.7, 0.05),
          // No structural damping; and a floating strip (no foundation) with light damping. (Not
          // both: with every clamp free that is an undamped strip 0.7 Hz from a resonance, where
          // even the clamp-only fast path and the full solve differ by 2e-9.)
          Variation(3.0e4, 1.3, 0.0),
          Variation(0.0, 1.3, 0.02),
          Variation(1.0e6, 5.0, 1.0)};
}

TEST(PlateSensorVariation, EqualsFullSolveOfTheVariedModel) {
  ExpectVariationsEqualFullSolve(CoarseOptions(), TypicalVariations(), 12);
}

// Un-normalised, so the overall stiffness factor s (1 + i eta) must come out right too.
TEST(PlateSensorVariation, EqualsFullSolveUnnormalised) {
  SensorOptions o = CoarseOptions();
  o.normalise = false;
  ExpectVariationsEqualFullSolve(o, TypicalVariations(), 6);
}

TEST(PlateSensorVariation, EqualsFullSolveOtherSupports) {
  SensorOptions o = CoarseOptions();
  o.fixed_support = Support::kSimplySupported;
  o.short_edge_start = Support::kClamped;
  o.short_edge_end = Support::kSimplySupported;
  o.load_cases[0].load_x = 0.3712;  // inside a section: the interior load goes through the series
  o.load_cases[0].load_patch_length = 0.0;  // point load
  o.length_grading = 1.0;
  o.width_grading = 2.0;
  o.normalise = false;
  ExpectVariationsEqualFullSolve(o, TypicalVariations(), 8);
}

// Above the foundation resonance (120 Hz: Re mu < 0, the series around mu = 0 still converges where
// |mu| < lambda_1) and on a floating strip, where the unpivoted block LDL^T may meet indefinite
// pivots and the residual check hands over to the pivoting LU.
TEST(PlateSensorVariation, EqualsFullSolveAboveResonance) {
  SensorOptions o = CoarseOptions();
  o.frequency_hz = 120.0;
  ExpectVariationsEqualFullSolve(o,
                                 {Variation(2.0e4, std::nullopt, std::nullopt),
                                  Variation(std::nullopt, 3.0, 0.05),
                                  Variation(1.0e6, 0.3, 0.2)},
                                 12);
}

// The pivoting LU of the condensed system (the LDL^T fallback) on its own.
TEST(PlateSensorVariation, EqualsFullSolveWithPivotingLu) {
  SensorOptions o = CoarseOptions();
  o.always_pivot = true;
  ExpectVariationsEqualFullSolve(o, TypicalVariations(), 6);
}

// Layers with different Poisson ratios: their bending matrices differ in shape, so the layers' own
// loss factors give a K_imag that is not proportional to K_real, and an unset loss factor takes
// the complex K_base (ContinuousCache::base[1]); the default laminate (one Poisson ratio) never
// does.
TEST(PlateSensorVariation, LayersOwnLossFactorsNotProportional) {
  SensorOptions o = CoarseOptions();
  o.layers[1].poisson_ratio = 0.3;
  o.layers[1].loss_factor = 0.4;
  const SensorModel model(o);
  std::vector<double> out(model.num_outputs());
  const std::vector<std::uint8_t> clamps(model.num_clamps(), 0);
  model.Profile(clamps, Variation(2.0e4, 1.5, 0.2), out);
  const std::size_t one_base = model.VariationPrecomputedBytes();
  model.Profile(clamps, Variation(2.0e4, 1.5, std::nullopt), out);
  EXPECT_GT(model.VariationPrecomputedBytes(), one_base);  // the second, complex base
  ExpectVariationsEqualFullSolve(o, TypicalVariations(), 8);
}

// FSDT through the continuous-unknowns path: its harmonic mass acts on w only (rotary inertia is
// modal only, element.hpp), so the series bound works with a semidefinite M; and the default
// laminate's shear stiffness carries the core's loss factor, so the layers' own factors take the
// complex K_base.
TEST(PlateSensorVariation, EqualsFullSolveFsdt) {
  SensorOptions o = CoarseOptions();
  o.theory = PlateTheory::kFsdt;
  o.element_order = 1;  // bilinear; the quadratic elements below
  ExpectVariationsEqualFullSolve(o, TypicalVariations(), 8);
}

// RZT through the continuous-unknowns path: its zigzag stiffnesses carry the core's loss factor
// as FSDT's shear does, so the layers' own factors take the complex K_base too.
TEST(PlateSensorVariation, EqualsFullSolveRzt) {
  SensorOptions o = CoarseOptions();
  o.theory = PlateTheory::kRzt;
  o.element_order = 1;  // bilinear; the quadratic elements below
  ExpectVariationsEqualFullSolve(o, TypicalVariations(), 8);
}

// Element order 2 (MITC9 / RZT9) through the continuous-unknowns path: the sections' mid-side
// node lines are interior dofs of the series and of the direct condensation alike (measured
// worst 3e-11 against kVariationTol, the floating undamped strip as at order 1).
TEST(PlateSensorVariation, EqualsFullSolveQuadratic) {
  for (PlateTheory theory : {PlateTheory::kFsdt, PlateTheory::kRzt}) {
    SensorOptions o = CoarseOptions();
    o.theory = theory;
    o.element_order = 2;
    o.elements_per_section = 2;
    o.elements_across_width = 1;
    ExpectVariationsEqualFullSolve(o, TypicalVariations(), 6);
  }
}

// The proportional default laminate needs one precompute for both loss-factor kinds.
TEST(PlateSensorVariation, ProportionalLaminateSharesOnePrecompute) {
  const SensorModel model(CoarseOptions());
  EXPECT_EQ(model.VariationPrecomputedBytes(), 0u);  // nothing before the first call
  std::vector<double> out(model.num_outputs());
  const std::vector<std::uint8_t> clamps(model.num_clamps(), 1);
  model.Profile(clamps, Variation(2.0e4, std::nullopt, 0.2), out);
  const std::size_t one_base = model.VariationPrecomputedBytes();
  EXPECT_GT(one_base, 0u);
  model.Profile(clamps, Variation(2.0e4, std::nullopt, std::nullopt), out);
  EXPECT_EQ(model.VariationPrecomputedBytes(), one_base);
}

// An empty variation is the clamp-only fast path itself; the model's own values given explicitly
// go through the per-call condensation and must agree with it to round-off.
TEST(PlateSensorVariation, ModelsOwnValuesEqualTheClampOnlyFastPath) {
  const SensorModel model(CoarseOptions());
  const SensorVariation own = Variation(model.options().foundation_stiffness, 1.0, std::nullopt);
  for (const int terms : model.VariationSeriesTerms(own)) EXPECT_GT(terms, 0);
  std::mt19937_64 rng(21);
  std::vector<double> fast(model.num_outputs());
  std::vector<double> empty(model.num_outputs());
  std::vector<double> explicit_own(model.num_outputs());
  double worst = 0.0;
  for (int i = 0; i < 20; ++i) {
    const auto clamps = RandomClamps(rng, model.num_clamps());
    model.Profile(clamps, fast);
    model.Profile(clamps, SensorVariation{}, empty);
    model.Profile(clamps, own, explicit_own);
    EXPECT_EQ(empty, fast);
    worst = std::max(worst, MaxRelativeDifference(explicit_own, fast));
  }
  std::printf("model's own values vs clamp-only fast path: worst %.2e\n", worst);
  EXPECT_LT(worst, kRoundOffTol);
}

// Where |mu| / lambda_1 > kMaxRatio (a much softer laminate, a much stiffer foundation) every state
// is condensed directly per call; the result is the same exact one.
TEST(PlateSensorVariation, DirectCondensationBeyondTheSeries) {
  const SensorModel model(CoarseOptions());
  const std::vector<SensorVariation> variations = {Variation(std::nullopt, 2e-3, std::nullopt),
                                                   Variation(5.0e8, std::nullopt, 0.3)};
  for (const SensorVariation& v : variations) {
    for (const int terms : model.VariationSeriesTerms(v)) EXPECT_EQ(terms, -1) << Describe(v);
  }
  ExpectVariationsEqualFullSolve(CoarseOptions(), variations, 8, kRoundOffTol);
}

// The series with the most terms it may use (|mu| / lambda_1 just below kMaxRatio): were the
// eigenvalue bound or the tail bound wrong, this is where the truncation would show.
TEST(PlateSensorVariation, SeriesAtItsLargestRatio) {
  const SensorModel model(CoarseOptions());
  const int most = ContinuousCondensation::TermsFor(ContinuousCondensation::kMaxRatio);
  SensorVariation v = Variation(std::nullopt, 1.0, 0.1);
  double s = 1.0;
  // Soften the laminate until the least stiff state's series is about to give way.
  while (model.VariationSeriesTerms(v)[0] >= 0) {
    v.stiffness_scale = s;
    if (model.VariationSeriesTerms(v)[0] >= most - 3) break;
    s *= 0.97;
  }
  const auto terms = model.VariationSeriesTerms(v);
  std::printf("s = %.4g: terms %d %d %d %d (at most %d)\n",
              s,
              terms[0],
              terms[1],
              terms[2],
              terms[3],
              most);
  ASSERT_GE(terms[0], most - 3);
  ExpectVariationsEqualFullSolve(CoarseOptions(), {v}, 8, kRoundOffTol);
}

// The term count is the smallest K with q^K <= kSeriesTol (1 - q), the tail bound of the series.
TEST(PlateSensorVariation, TermCountMeetsTheTailBound) {
  using CC = ContinuousCondensation;
  EXPECT_EQ(CC::TermsFor(0.0), 0);
  EXPECT_EQ(CC::TermsFor(CC::kMaxRatio * 1.0001), -1);
  for (double q = 1e-6; q <= CC::kMaxRatio; q *= 1.3) {
    const int k = CC::TermsFor(q);
    ASSERT_GE(k, 1) << q;
    EXPECT_LE(std::pow(q, k), CC::kSeriesTol * (1.0 - q) * (1.0 + 1e-12)) << q;
    if (k > 1) {
      EXPECT_GT(std::pow(q, k - 1), CC::kSeriesTol * (1.0 - q)) << q;
    }
  }
}

TEST(PlateSensorVariation, InvalidVariationsNameTheField) {
  std::string why;
  EXPECT_TRUE(SensorVariation{}.IsValid(&why));
  EXPECT_TRUE(Variation(0.0, 1e-6, 0.0).IsValid(&why));
  EXPECT_TRUE(Variation(1e15, 1e6, 10.0).IsValid(&why));
  EXPECT_FALSE(Variation(-1.0, std::nullopt, std::nullopt).IsValid(&why));
  EXPECT_EQ(why, "SensorVariation::foundation_stiffness = -1; must be in [0, 1e15] N/m^3");
  EXPECT_FALSE(Variation(std::nan(""), std::nullopt, std::nullopt).IsValid(&why));
  EXPECT_FALSE(Variation(std::nullopt, 0.0, std::nullopt).IsValid(&why));
  EXPECT_EQ(why, "SensorVariation::stiffness_scale = 0; must be in [1e-6, 1e6]");
  EXPECT_FALSE(Variation(std::nullopt, INFINITY, std::nullopt).IsValid(&why));
  EXPECT_FALSE(Variation(std::nullopt, std::nullopt, -0.1).IsValid(&why));
  EXPECT_EQ(why, "SensorVariation::loss_factor = -0.1; must be in [0, 10]");
  const SensorModel model(CoarseOptions());
  std::vector<double> out(model.num_outputs());
  const std::vector<std::uint8_t> clamps(model.num_clamps(), 0);
  try {
    model.Profile(clamps, Variation(std::nullopt, 2e6, std::nullopt), out);
    FAIL() << "expected combabc::Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    EXPECT_EQ(e.field(), "SensorVariation::stiffness_scale");
  }
  const std::vector<std::uint8_t> short_clamps(model.num_clamps() - 1, 0);
  EXPECT_THROW(model.Profile(short_clamps, Variation(1e4, std::nullopt, std::nullopt), out), Error);
}

TEST(PlateSensorVariation, ApplyVariationSetsEveryLayer) {
  const SensorOptions base;
  const SensorOptions varied = ApplyVariation(base, Variation(1e3, 2.0, 0.7));
  EXPECT_EQ(varied.foundation_stiffness, 1e3);
  EXPECT_EQ(varied.foundation_loss_factor, base.foundation_loss_factor);
  ASSERT_EQ(varied.layers.size(), base.layers.size());
  for (std::size_t k = 0; k < base.layers.size(); ++k) {
    EXPECT_EQ(varied.layers[k].youngs_modulus, 2.0 * base.layers[k].youngs_modulus);
    EXPECT_EQ(varied.layers[k].loss_factor, 0.7);
    EXPECT_EQ(varied.layers[k].density, base.layers[k].density);
  }
  const SensorOptions same = ApplyVariation(base, SensorVariation{});
  EXPECT_EQ(same.layers[1].loss_factor, base.layers[1].loss_factor);
  EXPECT_EQ(same.foundation_stiffness, base.foundation_stiffness);
}

// Each row depends only on its configuration and variation, whatever the threads; the lazily built
// precomputes are built once even when the first calls race (a fresh model per thread count).
TEST(PlateSensorVariation, BatchMatchesSingleCallsForAnyThreadCount) {
  SensorOptions o = CoarseOptions();
  o.layers[1].poisson_ratio = 0.3;  // both precomputes: an explicit loss factor and the layers'
  std::mt19937_64 rng(4);
  const std::size_t n = 29;
  const std::size_t nk = 36;
  std::vector<std::uint8_t> clamps;
  std::vector<SensorVariation> variations;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = RandomClamps(rng, static_cast<int>(nk));
    clamps.insert(clamps.end(), c.begin(), c.end());
    SensorVariation v = Variation(1e4 * std::pow(20.0, unit(rng)), 0.5 + unit(rng), std::nullopt);
    if (i % 2 == 0) v.loss_factor = 0.3 * unit(rng);
    if (i == 5) v = SensorVariation{};     // the clamp-only fast path
    if (i == 7) v.stiffness_scale = 2e-3;  // direct condensation
    variations.push_back(v);
  }
  const SensorModel reference(o);
  const std::size_t no = static_cast<std::size_t>(reference.num_outputs());
  std::vector<double> single(n * no);
  for (std::size_t i = 0; i < n; ++i) {
    reference.Profile(std::span(clamps).subspan(i * nk, nk),
                      variations[i],
                      std::span(single).subspan(i * no, no));
  }
  for (int threads : {1, 2, 3}) {
    const SensorModel model(o);
    std::vector<double> batch(n * no);
    model.ProfileBatch(clamps, variations, n, batch, threads);
    EXPECT_EQ(batch, single) << threads << " threads";
  }
  std::vector<double> batch(n * no);
  EXPECT_THROW(reference.ProfileBatch(clamps, std::span(variations).first(n - 1), n, batch, 1),
               Error);
}

// The estimate that the config adds for a mixed run must track what the continuous precompute
// really keeps (its containers, VariationPrecomputedBytes): above it (it also counts the series'
// terms while they are built) but within 2.5 x, for real tables (the default laminate, whose
// loss factors are proportional; or loss_factor unknown) and complex ones (layers with their own,
// non-proportional loss factors).
TEST(SensorVariation, MemoryEstimateBoundsTheContinuousPrecompute) {
  struct Case {
    int along, across;
    bool own_loss_factors;  // a laminate whose imaginary stiffness is not proportional
    std::optional<double> loss_factor;
    PlateTheory theory = PlateTheory::kKirchhoff;
    int element_order = 1;
    // 3: two more load cases (docs/model.md, "Several load cases"), one on the default outputs and
    // one, loading a section inside, on a line of its own.
    int load_cases = 1;
  };
  // RZT: 5 dofs per node, and the default laminate is not proportionally damped in it.
  for (const Case& c : {Case{4, 2, false, std::nullopt},
                        Case{6, 4, false, std::nullopt},
                        Case{4, 2, true, std::nullopt},
                        Case{4, 2, true, 0.05},
                        Case{4, 2, false, std::nullopt, PlateTheory::kRzt},
                        Case{2, 1, false, std::nullopt, PlateTheory::kRzt, 2},
                        Case{4, 2, false, std::nullopt, PlateTheory::kKirchhoff, 1, 3}}) {
    SCOPED_TRACE(std::to_string(c.along) + " x " + std::to_string(c.across) +
                 (c.own_loss_factors ? ", own loss factors" : "") +
                 (c.loss_factor ? ", loss_factor unknown" : "") + ", " + ToString(c.theory) + ", " +
                 std::to_string(c.load_cases) + " load cases");
    SensorOptions o;
    o.theory = c.theory;
    o.element_order = c.element_order;
    o.elements_per_section = c.along;
    o.elements_across_width = c.across;
    if (c.own_loss_factors) {
      o.layers[1].loss_factor = 0.3;
      o.layers[1].poisson_ratio = 0.3;  // the others: 0.45
    }
    if (c.load_cases == 3) {
      o.load_cases.resize(3);
      o.load_cases[1].load_x = 0.70;
      o.load_cases[2].load_x = 0.3712;
      o.load_cases[2].output_y_fraction = 0.25;
    }
    const SensorModel model(o);
    ASSERT_EQ(model.VariationPrecomputedBytes(), 0u);
    std::vector<std::uint8_t> clamps(static_cast<std::size_t>(model.num_clamps()), 1);
    std::vector<double> out(static_cast<std::size_t>(model.num_outputs()));
    model.Profile(clamps, Variation(6e4, std::nullopt, c.loss_factor), out);
    const auto kept = static_cast<double>(model.VariationPrecomputedBytes());
    ASSERT_GT(kept, 0.0);
    const double estimate = o.EstimatedContinuousMemoryBytes(c.loss_factor.has_value());
    EXPECT_GE(estimate, kept);
    EXPECT_LE(estimate, 2.5 * kept);
  }
}

}  // namespace
}  // namespace combabc::plate
