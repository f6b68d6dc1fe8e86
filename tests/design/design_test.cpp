// combabc design's expected information gain (design/experiment_design.hpp) against the
// exhaustive computation on a sensor small enough to enumerate: the tiny 3 + 3 clamp sensor
// (64 configurations) with a few candidate loads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <vector>

#include "combabc/design/experiment_design.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/rng/random_stream.hpp"
#include "combabc/services/design.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

constexpr double kSigma = 0.03;

struct TinyDesign {
  design::Population population;  // every configuration, prior mass 1/64
  std::vector<design::CandidateProfiles> candidates;
};

TinyDesign MakeSetup() {
  plate::SensorOptions o;
  o.clamps_per_edge = 3;
  o.elements_per_section = 2;
  o.elements_across_width = 2;
  o.normalise = true;
  // A centreline load (mirror pairs indistinguishable), off-centre loads, a short scan.
  const double loads[][3] = {
      {0.45, 0.5, 0.0}, {0.15, 0.5, 0.0}, {0.30, 0.25, 0.0}, {0.75, 0.5, 0.6}};
  o.load_cases.clear();
  for (const auto& l : loads) {
    plate::LoadCase c;
    c.load_x = l[0];
    c.load_y_fraction = l[1];
    c.output_positions.clear();
    for (int k = 0; k <= 18; ++k) {
      const double x = 0.05 * k;
      if (x >= l[2]) c.output_positions.push_back(x);
    }
    o.load_cases.push_back(c);
  }
  const plate::SensorModel model(o);
  TinyDesign s;
  s.population.dimension = 6;
  for (int code = 0; code < 64; ++code) {
    for (int k = 0; k < 6; ++k) s.population.bits.push_back((code >> k) & 1);
    s.population.weights.push_back(1.0 / 64);
  }
  std::vector<double> all(64 * static_cast<std::size_t>(model.num_outputs()));
  model.ProfileBatch(s.population.bits, 64, all);
  for (std::size_t c = 0; c < o.load_cases.size(); ++c) {
    design::CandidateProfiles p;
    p.points = static_cast<int>(o.load_cases[c].output_positions.size());
    for (int i = 0; i < 64; ++i) {
      const std::size_t begin =
          static_cast<std::size_t>(i) * static_cast<std::size_t>(model.num_outputs()) +
          o.OutputOffset(c);
      const auto row = all.begin() + static_cast<std::ptrdiff_t>(begin);
      p.values.insert(p.values.end(), row, row + p.points);
    }
    s.candidates.push_back(std::move(p));
  }
  return s;
}

// The exhaustive expected gain: every configuration as the truth (its prior mass), `draws` noise
// draws each, the exact posterior over all 64. Returns the gain and its standard error.
std::pair<double, double> Exhaustive(const TinyDesign& s, int c, int draws) {
  const design::CandidateProfiles& p = s.candidates[static_cast<std::size_t>(c)];
  const auto m = static_cast<std::size_t>(p.points);
  const double h0 = design::MarginalEntropy(design::Marginals(s.population));
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  std::vector<double> y(m), logw(64);
  for (int t = 0; t < 64; ++t) {
    for (int r = 0; r < draws; ++r) {
      RandomStream rng(
          99, static_cast<std::uint64_t>(c), static_cast<std::uint64_t>(t * draws + r));
      for (std::size_t k = 0; k < m; ++k) y[k] = p.values[t * m + k] + kSigma * rng.Normal();
      double top = -1e300;
      for (int i = 0; i < 64; ++i) {
        double sse = 0.0;
        for (std::size_t k = 0; k < m; ++k) {
          const double d = y[k] - p.values[i * m + k];
          sse += d * d;
        }
        logw[i] = -sse / (2 * kSigma * kSigma);
        top = std::max(top, logw[i]);
      }
      std::vector<double> marg(6, 0.0);
      double total = 0.0;
      for (int i = 0; i < 64; ++i) {
        const double w = std::exp(logw[i] - top);
        total += w;
        for (int k = 0; k < 6; ++k) marg[k] += ((i >> k) & 1) ? w : 0.0;
      }
      for (double& v : marg) v /= total;
      const double gain = h0 - design::MarginalEntropy(marg);
      sum += gain;
      sum2 += gain * gain;
      ++n;
    }
  }
  const double mean = sum / n;
  return {mean, std::sqrt((sum2 / n - mean * mean) / (n - 1))};
}

TEST(Design, InformationGainAgreesWithTheExhaustiveComputation) {
  const TinyDesign s = MakeSetup();
  design::DesignOptions options;
  options.noise_sigma = kSigma;
  options.truths = 400;
  options.seed = 5;
  const design::DesignResult r = design::ScoreCandidates(s.population, s.candidates, options);
  EXPECT_NEAR(r.prior_entropy, 6.0, 1e-12);
  int design_top = 0, exhaustive_top = 0;
  double best = -1.0;
  for (int c = 0; c < static_cast<int>(s.candidates.size()); ++c) {
    const auto [gain, se] = Exhaustive(s, c, 20);
    const design::Score& score = r.scores[static_cast<std::size_t>(c)];
    // Within 4 combined standard errors (the Monte-Carlo error of both).
    const double bound = 4.0 * std::hypot(score.information_gain_se, se);
    EXPECT_NEAR(score.information_gain, gain, bound) << "candidate " << c;
    EXPECT_GT(score.information_gain_se, 0.0);
    EXPECT_LT(score.information_gain_se, 0.2);
    if (gain > best) {
      best = gain;
      exhaustive_top = c;
    }
    if (score.information_gain > r.scores[static_cast<std::size_t>(design_top)].information_gain) {
      design_top = c;
    }
  }
  EXPECT_EQ(design_top, exhaustive_top);
  EXPECT_EQ(r.selected.front(), design_top);
}

TEST(Design, CentrelineLoadAndScanCannotSeparateMirrorClamps) {
  // Clamp k and its mirror k + 3 get the same identifiability from the centreline experiment,
  // while the off-centre load separates them (paper section 6: repeat with another impact).
  const TinyDesign s = MakeSetup();
  design::DesignOptions options;
  options.noise_sigma = kSigma;
  options.truths = 300;
  const design::DesignResult r = design::ScoreCandidates(s.population, s.candidates, options);
  const design::Score& centre = r.scores[0];
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(centre.identifiability[k], centre.identifiability[k + 3], 0.1) << k;
    EXPECT_LT(centre.identifiability[k], 0.75) << k;  // a mirror pair stays split
  }
  EXPECT_GT(r.scores[2].information_gain, centre.information_gain + 1.0);
  EXPECT_LT(r.scores[2].wrong, 0.1);  // confidently wrong is rare at this noise
}

TEST(Design, TheSameSeedGivesTheSameScoresForAnyThreads) {
  const TinyDesign s = MakeSetup();
  design::DesignOptions options;
  options.noise_sigma = kSigma;
  options.truths = 100;
  options.select = 2;
  options.threads = 1;
  const design::DesignResult one = design::ScoreCandidates(s.population, s.candidates, options);
  options.threads = 3;
  const design::DesignResult three = design::ScoreCandidates(s.population, s.candidates, options);
  ASSERT_EQ(one.scores.size(), three.scores.size());
  for (std::size_t c = 0; c < one.scores.size(); ++c) {
    EXPECT_EQ(one.scores[c].information_gain, three.scores[c].information_gain);
    EXPECT_EQ(one.scores[c].identifiability, three.scores[c].identifiability);
  }
  EXPECT_EQ(one.selected, three.selected);
  EXPECT_EQ(one.cumulative.back().information_gain, three.cumulative.back().information_gain);
}

TEST(Design, RefusesInconsistentInput) {
  TinyDesign s = MakeSetup();
  design::DesignOptions options;
  options.noise_sigma = 0.0;
  EXPECT_THROW(design::ScoreCandidates(s.population, s.candidates, options), std::invalid_argument);
  options.noise_sigma = kSigma;
  s.candidates[1].values.pop_back();
  EXPECT_THROW(design::ScoreCandidates(s.population, s.candidates, options), std::invalid_argument);
}

// `combabc design` on a plate without foundation, statically loaded: the configuration with no
// clamp fixed leaves it free to move as a rigid body, and its system is singular. That one
// configuration is left out (a run fails it too) and the other 63 ranked; before, it aborted the
// whole design with an error that named no file or key.
TEST(Design, ASingularConfigurationIsLeftOutNotFatal) {
  const testing::TempFolder folder("design-singular");
  std::ofstream(folder / "design.toml") << "[model]\nfoundation_stiffness = 0\n"
                                           "[model.clamps]\nper_edge = 3\n"
                                           "[model.mesh]\nelements_per_section = 2\n"
                                           "elements_across_width = 2\n"
                                           "[model.load]\nfrequency = 0\n"
                                           "[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"area\"\n"
                                           "[design]\nload_x = [30, 45]\ntruths = 20\nselect = 1\n"
                                           "noise = 0.02\n";
  services::DesignRequest request;
  request.config_path = folder / "design.toml";
  request.output_directory = folder / "out";
  request.threads = 1;
  request.figure = false;
  const services::DesignOutcome o = services::RunDesign(request);
  EXPECT_EQ(o.singular, 1U);
  EXPECT_NE(o.singular_reason.find("singular"), std::string::npos) << o.singular_reason;
  EXPECT_EQ(o.particles, 63U);
  EXPECT_EQ(o.noise_sigma, 0.02);  // the header line prints it (issue 34)
  ASSERT_EQ(o.result.scores.size(), 2U);
  for (const design::Score& s : o.result.scores) EXPECT_GT(s.information_gain, 0.0);
}

}  // namespace
}  // namespace combabc
