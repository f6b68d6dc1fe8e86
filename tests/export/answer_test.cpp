// The answer in numbers (export/answer.hpp): against a brute force on an enumerable toy, against
// the estimators' formulas written here on a sampled run, the verdict thresholds, the wave an
// early stop leaves, the terminal layout, and the sensor's clamp positions from a run's config.
#include "combabc/export/answer.hpp"
#include "combabc/export/export.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <sstream>

#include "combabc/export/fit_checks.hpp"
#include "combabc/export/strip.hpp"
#include "combabc/samplers/enumeration.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "combabc/services/history_tools.hpp"
#include "history/fake_run.hpp"
#include "samplers/toy_models.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;

constexpr int kBits = 6;
constexpr double kEps = 2.0;

std::string BitString(int c, int bits) {
  std::string s;
  for (int k = 0; k < bits; ++k) s += (c >> k) & 1 ? '1' : '0';
  return s;
}

// An enumeration's history: every accepted configuration of a 6-bit toy, as combabc enumerate
// stores it (services/enumerate.cpp).
struct EnumeratedToy {
  std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.8, 0.2};
  testing::WeightedL1Distance distance{{1, 0, 1, 1, 0, 0}, {3, 1, 1, 1, 0.5, 0.5}, 1, 2, 0.5};
  testing::IdentitySimulator simulator{kBits};
  ParameterSpace space = [this] {
    BinarySpaceOptions o;
    o.dimension = kBits;
    o.prior_one = prior;
    return ParameterSpace(BinarySpace(o));
  }();
  RunMetadata metadata;
  RunHistory history;

  EnumeratedToy() {
    EnumerationOptions options;
    options.thresholds = {kEps};
    options.threads = 1;
    const EnumerationResult r = Enumerate({&space, &simulator, &distance}, options);
    history.waves.push_back(r.Wave(options.thresholds, prior));
    history.summary.termination = Termination::kEnumerated;
    metadata.termination = ToString(Termination::kEnumerated);
    metadata.estimator = "importance";
    metadata.dimension = kBits;
    for (int k = 1; k <= kBits; ++k) metadata.bit_names.push_back("b" + std::to_string(k));
  }
};

TEST(Answer, OfAnEnumerationIsTheExactPosteriorOfABruteForce) {
  const EnumeratedToy toy;
  // Brute force, independently of Enumerate: every configuration's prior mass, kept if accepted.
  std::map<std::string, double> mass;
  std::vector<double> ones(kBits, 0.0);
  double z = 0.0;
  std::vector<double> y(kBits);
  for (int c = 0; c < (1 << kBits); ++c) {
    double p = 1.0;
    for (int k = 0; k < kBits; ++k) {
      y[k] = (c >> k) & 1;
      p *= y[k] != 0.0 ? toy.prior[k] : 1.0 - toy.prior[k];
    }
    double d = 0.0;
    toy.distance.Evaluate(y, std::span(&d, 1));
    if (d > kEps) continue;
    mass[BitString(c, kBits)] = p;
    z += p;
    for (int k = 0; k < kBits; ++k) ones[k] += p * y[k];
  }
  ASSERT_GT(mass.size(), 10u);  // more accepted configurations than the answer lists

  const Answer a = SummariseAnswer(toy.metadata, toy.history);
  EXPECT_TRUE(a.exact);
  EXPECT_TRUE(a.complete);
  EXPECT_EQ(a.wave, 1);
  EXPECT_EQ(a.particles, static_cast<std::int64_t>(mass.size()));
  ASSERT_EQ(a.bits.size(), static_cast<std::size_t>(kBits));
  for (int k = 0; k < kBits; ++k) {
    const AnswerBit& b = a.bits[k];
    EXPECT_EQ(b.number, k + 1);
    EXPECT_EQ(b.name, "b" + std::to_string(k + 1));
    EXPECT_FALSE(b.position);
    EXPECT_NEAR(b.p_one, ones[k] / z, 1e-12) << b.name;
    EXPECT_EQ(b.mc_se, 0.0);  // exact
    EXPECT_EQ(b.verdict, VerdictOf(ones[k] / z));
  }
  // Bit 1 weighs 3 > eps away from its target 1: fixed with certainty.
  EXPECT_EQ(a.bits[0].verdict, Verdict::kFixed);
  // The ten largest masses, largest first, exact (no standard error).
  std::vector<std::pair<double, std::string>> sorted;
  sorted.reserve(mass.size());
  for (const auto& [bits, p] : mass) sorted.emplace_back(p / z, bits);
  std::sort(
      sorted.begin(), sorted.end(), [](const auto& l, const auto& r) { return l.first > r.first; });
  ASSERT_EQ(a.top_configurations.size(), kAnswerConfigurations);
  for (std::size_t i = 0; i < kAnswerConfigurations; ++i) {
    const AnswerConfiguration& c = a.top_configurations[i];
    EXPECT_NEAR(c.mass, sorted[i].first, 1e-12) << i;
    EXPECT_NEAR(c.mass, mass.at(c.bits) / z, 1e-12) << c.bits;
    EXPECT_FALSE(c.mass_se);
    for (const std::string& name : c.fixed) {
      EXPECT_EQ(c.bits[static_cast<std::size_t>(std::stoi(name.substr(1)) - 1)], '1') << name;
    }
  }
  ASSERT_EQ(a.per_wave.size(), 1u);
  EXPECT_EQ(a.per_wave[0].simulations, 1 << kBits);

  const std::string json = AnswerJson(a);
  EXPECT_NE(json.find("\"exact\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"mass_se\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"position\": null"), std::string::npos) << json;
  const std::string text = AnswerText(a);
  EXPECT_NE(text.find("answer: exact"), std::string::npos) << text;
  EXPECT_NE(text.find(" b1    1.00        fixed"), std::string::npos) << text;
  // Exact: no per-quantity ESS.
  EXPECT_FALSE(a.per_wave[0].bits_ess);
  EXPECT_EQ(text.find("ESS bits"), std::string::npos) << text;
}

// A run that named no bits: the answer names them as the export's particles.csv columns do
// (BitName, "bit k" from 1), in the bits and in the most probable configurations alike.
TEST(Answer, UnnamedBitsAreNamedAsTheExportNamesThem) {
  EnumeratedToy toy;
  toy.metadata.bit_names.clear();
  const Answer a = SummariseAnswer(toy.metadata, toy.history);
  ASSERT_EQ(a.bits.size(), static_cast<std::size_t>(kBits));
  for (std::size_t k = 0; k < a.bits.size(); ++k) {
    EXPECT_EQ(a.bits[k].name, BitName(toy.metadata, k));
    EXPECT_EQ(a.bits[k].name, "bit " + std::to_string(k + 1));
  }
  ASSERT_FALSE(a.top_configurations.empty());
  for (const AnswerConfiguration& c : a.top_configurations) {
    for (const std::string& name : c.fixed) {
      ASSERT_EQ(name.rfind("bit ", 0), 0u) << name;
      EXPECT_EQ(c.bits[static_cast<std::size_t>(std::stoi(name.substr(4)) - 1)], '1') << name;
    }
  }
}

// A sampled run (the fake 36-clamp run, three complete waves): each estimator's marginals and
// configuration masses from the particles, with delta-method standard errors
// sqrt(sum w^2 (x - p)^2) / sum w: for the paper estimator's equal weights sqrt(p (1 - p) / n).
TEST(Answer, OfASampledRunIsTheEstimatorsWithDeltaMethodErrors) {
  testing::FakeRunOptions options;
  options.per_wave = 40;
  const RunMetadata paper_metadata = testing::MakeFakeMetadata(options);
  for (const char* estimator : {"paper", "importance"}) {
    SCOPED_TRACE(estimator);
    RunMetadata m = paper_metadata;
    m.estimator = estimator;
    RunHistory h = testing::MakeFakeHistory(options);
    const bool paper = m.estimator == "paper";
    for (WaveRecord& w : h.waves) {
      ComputeWaveStatistics(w, paper ? Estimator::kPaper : Estimator::kImportance);
    }
    const WaveRecord& last = h.waves.back();
    const auto n = last.particles.size();
    std::vector<double> weight(n, 1.0);
    if (!paper) {
      for (std::size_t i = 0; i < n; ++i) weight[i] = std::exp(last.particles[i].log_weight);
    }
    double sum = 0.0;
    double squares_w = 0.0;
    for (double w : weight) {
      sum += w;
      squares_w += w * w;
    }
    // A probability's interval reaches at least 3 / ESS from the nearer edge (the rule of three,
    // WeightedProbability).
    const double floor = std::min(3.0 * squares_w / (sum * sum), 0.5);
    // The delta method's standard error of the weighted mean of x_i = counts(particle i).
    auto error = [&](double p, const std::function<bool(std::size_t)>& counts) {
      double squares = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        const double x = counts(i) ? 1.0 : 0.0;
        squares += weight[i] * weight[i] * (x - p) * (x - p);
      }
      return std::sqrt(squares) / sum;
    };
    std::map<std::string, double> mass;
    std::vector<double> ones(options.dimension, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      std::string bits;
      for (std::size_t k = 0; k < last.particles[i].theta.bits.size(); ++k) {
        bits += last.particles[i].theta.bits[k] ? '1' : '0';
        ones[k] += last.particles[i].theta.bits[k] * weight[i] / sum;
      }
      mass[bits] += weight[i] / sum;
    }

    const Answer a = SummariseAnswer(m, h);
    EXPECT_FALSE(a.exact);
    EXPECT_EQ(a.wave, options.waves);
    EXPECT_EQ(a.estimator, m.estimator);
    ASSERT_EQ(a.bits.size(), ones.size());
    double min_ess = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < ones.size(); ++k) {
      EXPECT_NEAR(a.bits[k].p_one, ones[k], 1e-12) << k;
      const double se =
          error(ones[k], [&](std::size_t i) { return last.particles[i].theta.bits[k] != 0; });
      EXPECT_NEAR(a.bits[k].mc_se, std::max(se, floor - std::min(ones[k], 1 - ones[k])), 1e-12)
          << k;
      if (paper) {
        EXPECT_NEAR(se, std::sqrt(ones[k] * (1 - ones[k]) / static_cast<double>(n)), 1e-12) << k;
      }
      if (se > 0) min_ess = std::min(min_ess, ones[k] * (1 - ones[k]) / (se * se));
    }
    // The bits' ESS: the smallest per-bit Var_w / SE^2 (the particles for equal weights).
    ASSERT_TRUE(a.per_wave.back().bits_ess);
    EXPECT_NEAR(*a.per_wave.back().bits_ess, min_ess, 1e-6 * min_ess);
    if (paper) {
      EXPECT_NEAR(min_ess, static_cast<double>(n), 1e-6);
    }
    ASSERT_FALSE(a.top_configurations.empty());
    for (const AnswerConfiguration& c : a.top_configurations) {
      EXPECT_NEAR(c.mass, mass.at(c.bits), 1e-12);
      ASSERT_TRUE(c.mass_se);
      const double se = error(c.mass, [&](std::size_t i) {
        for (std::size_t b = 0; b < c.bits.size(); ++b) {
          if ((c.bits[b] == '1') != (last.particles[i].theta.bits[b] != 0)) return false;
        }
        return true;
      });
      EXPECT_NEAR(*c.mass_se, std::max(se, floor - std::min(c.mass, 1 - c.mass)), 1e-12) << c.bits;
    }
    ASSERT_EQ(a.per_wave.size(), static_cast<std::size_t>(options.waves));
    for (std::size_t t = 0; t < a.per_wave.size(); ++t) {
      EXPECT_EQ(a.per_wave[t].wave, static_cast<int>(t) + 1);
      EXPECT_EQ(a.per_wave[t].simulations, h.waves[t].candidates);
      EXPECT_DOUBLE_EQ(a.per_wave[t].ess, h.waves[t].ess);
    }
  }
}

// A run with continuous parameters: each real's mean and sd with their delta-method errors and
// the mean's ESS, per wave the bits' and each real's ESS, on the terminal and in the JSON.
TEST(Answer, RealsGetDeltaMethodErrorsAndEveryQuantityItsEss) {
  testing::FakeRunOptions options;
  options.per_wave = 40;
  options.reals = 2;
  RunMetadata m = testing::MakeFakeMetadata(options);
  m.estimator = "importance";
  RunHistory h = testing::MakeFakeHistory(options);
  for (WaveRecord& w : h.waves) ComputeWaveStatistics(w, Estimator::kImportance);
  const WaveRecord& last = h.waves.back();
  std::vector<double> weights, values;
  for (const Particle& p : last.particles) {
    weights.push_back(p.weight);
    values.push_back(p.theta.reals[1]);
  }
  const Answer a = SummariseAnswer(m, h);
  ASSERT_EQ(a.reals.size(), 2u);
  const WeightedMoment mean = WeightedMean(weights, values);
  const WeightedMoment sd = WeightedSd(weights, values);
  EXPECT_NEAR(a.reals[1].mean, mean.value, 1e-9 * std::abs(mean.value));
  EXPECT_DOUBLE_EQ(a.reals[1].mc_se, mean.se);
  EXPECT_DOUBLE_EQ(a.reals[1].sd_se, sd.se);
  EXPECT_DOUBLE_EQ(a.reals[1].ess, mean.ess);
  ASSERT_EQ(a.per_wave.back().reals_ess.size(), 2u);
  EXPECT_DOUBLE_EQ(a.per_wave.back().reals_ess[1], mean.ess);
  ASSERT_TRUE(a.per_wave.back().bits_ess);

  const std::string text = AnswerText(a);
  for (const char* expected : {"(delta method; ESS of the bits >= ",
                               "sd ± standard error (delta method), ESS",
                               "\n ESS bits     ",
                               "\n ESS stiffness_1 ",
                               "\n ESS stiffness_2 ",
                               "\n simulations "}) {
    EXPECT_NE(text.find(expected), std::string::npos) << expected << " in\n" << text;
  }
  const std::string json = AnswerJson(a);
  for (const char* expected : {"\"sd_se\": ", "\"ess_bits\": ", "\"ess_reals\": ["}) {
    EXPECT_NE(json.find(expected), std::string::npos) << expected << " in\n" << json;
  }
  // The quantiles: of the same particles under the same weights (AnswerQuantile, checked below).
  EXPECT_EQ(a.reals[1].q05, AnswerQuantile(values, weights, 0.05));
  EXPECT_EQ(a.reals[1].median, AnswerQuantile(values, weights, 0.5));
  EXPECT_EQ(a.reals[1].q95, AnswerQuantile(values, weights, 0.95));
  EXPECT_LT(a.reals[1].q05, a.reals[1].median);
  EXPECT_LT(a.reals[1].median, a.reals[1].q95);
  EXPECT_NE(json.find("\"q05\": "), std::string::npos) << json;
  EXPECT_NE(json.find("\"median\": "), std::string::npos) << json;
  EXPECT_NE(json.find("\"q95\": "), std::string::npos) << json;
}

// The weighted quantile by hand: values 3, 1, 2 weighing 1, 1, 2 sort to 1 (1), 2 (2), 3 (1) of
// 4; a negative weight counts as 0, and without a positive weight there is no quantile.
TEST(Answer, QuantilesInvertTheWeightedDistribution) {
  const std::vector<double> values = {3.0, 1.0, 2.0};
  EXPECT_EQ(AnswerQuantile(values, {1.0, 1.0, 2.0}, 0.25), 1.0);  // 1 of 4 at or below 1
  EXPECT_EQ(AnswerQuantile(values, {1.0, 1.0, 2.0}, 0.26), 2.0);
  EXPECT_EQ(AnswerQuantile(values, {1.0, 1.0, 2.0}, 0.75), 2.0);  // 3 of 4 at or below 2
  EXPECT_EQ(AnswerQuantile(values, {1.0, 1.0, 2.0}, 0.95), 3.0);
  EXPECT_EQ(AnswerQuantile(values, {1.0, -5.0, 2.0}, 0.05), 2.0);  // 1 carries nothing
  EXPECT_TRUE(std::isnan(AnswerQuantile(values, {0.0, -1.0, 0.0}, 0.5)));
  EXPECT_TRUE(std::isnan(AnswerQuantile({}, {}, 0.5)));
}

// Signed (multi-fidelity) weights: every standard error is the delta-method one of the
// self-normalised estimate, sqrt(sum w^2 (x - p)^2) / sum w, computed here from the particles;
// sqrt(p (1 - p) / ESS) would understate it.
TEST(Answer, SignedWeightsGetTheSelfNormalisedError) {
  testing::FakeRunOptions options;
  options.per_wave = 40;
  RunMetadata m = testing::MakeFakeMetadata(options);
  m.estimator = "importance";
  RunHistory h = testing::MakeFakeHistory(options);
  WaveRecord& last = h.waves.back();
  // A few false positives (1 - 1 / 0.5 = -1) and false negatives (1 / 0.25 = 4).
  for (std::size_t i = 0; i < last.particles.size(); ++i) {
    last.particles[i].multiplier = i % 7 == 0 ? -1.0 : (i % 5 == 0 ? 4.0 : 1.0);
  }
  for (WaveRecord& w : h.waves) ComputeWaveStatistics(w, Estimator::kImportance);
  double sum = 0.0;
  double squares_w = 0.0;
  for (const Particle& q : last.particles) {
    sum += q.weight;
    squares_w += q.weight * q.weight;
  }
  // The rule of three: 3 / ESS with the signed weights' ESS (WeightedProbability).
  const double floor = std::min(3.0 * squares_w / (sum * sum), 0.5);
  auto error = [&](double p, const std::function<bool(const Particle&)>& counts) {
    double squares = 0.0;
    for (const Particle& q : last.particles) {
      const double x = counts(q) ? 1.0 : 0.0;
      squares += q.weight * q.weight * (x - p) * (x - p);
    }
    return std::sqrt(squares) / sum;
  };
  const Answer a = SummariseAnswer(m, h);
  bool differs = false;
  for (std::size_t k = 0; k < a.bits.size(); ++k) {
    const double expected =
        error(a.bits[k].p_one, [k](const Particle& q) { return q.theta.bits[k] != 0; });
    const double edge = std::min(a.bits[k].p_one, 1 - a.bits[k].p_one);
    EXPECT_NEAR(a.bits[k].mc_se, std::max(expected, floor - edge), 1e-12) << k;
    const double naive = std::sqrt(a.bits[k].p_one * (1 - a.bits[k].p_one) / last.ess);
    differs |= std::abs(expected - naive) > 1e-3;
  }
  EXPECT_TRUE(differs);
  for (const AnswerConfiguration& c : a.top_configurations) {
    ASSERT_TRUE(c.mass_se);
    const double expected = error(c.mass, [&c](const Particle& q) {
      for (std::size_t b = 0; b < c.bits.size(); ++b) {
        if ((c.bits[b] == '1') != (q.theta.bits[b] != 0)) return false;
      }
      return true;
    });
    EXPECT_NEAR(*c.mass_se, std::max(expected, floor - std::min(c.mass, 1 - c.mass)), 1e-12)
        << c.bits;
  }
}

// Signed weights can give a configuration a raw mass above 1 and another one below 0 (issue 35's
// 1.060 and -0.060): the answer shows masses in [0, 1], each with an error that covers its raw
// estimate, in the terminal's text and in the JSON.
TEST(Answer, SignedConfigurationMassesStayInZeroOneWithErrorsCoveringTheRawEstimate) {
  testing::FakeRunOptions options;
  options.per_wave = 40;
  RunMetadata m = testing::MakeFakeMetadata(options);
  m.estimator = "paper";
  RunHistory h = testing::MakeFakeHistory(options);
  WaveRecord& last = h.waves.back();
  // Every particle one configuration but three false positives of another (multiplier -1): raw
  // masses 40 / 37 = 1.08 and -3 / 37.
  const std::vector<std::uint8_t> bits = last.particles.front().theta.bits;
  std::vector<std::uint8_t> other = bits;
  other[0] = !other[0];
  for (std::size_t i = 0; i < last.particles.size(); ++i) {
    const bool negative = i < 3;
    last.particles[i].theta.bits = negative ? other : bits;
    last.particles[i].multiplier = negative ? -1.0 : 1.0;
  }
  ComputeWaveStatistics(last, Estimator::kPaper);
  const double raw_top = 37.0 / 34.0;  // 37 of weight 1 over the signed sum 37 - 3
  const Answer a = SummariseAnswer(m, h);
  ASSERT_EQ(a.top_configurations.size(), 2u);
  for (const AnswerConfiguration& c : a.top_configurations) {
    EXPECT_GE(c.mass, 0.0) << c.bits;
    EXPECT_LE(c.mass, 1.0) << c.bits;
    ASSERT_TRUE(c.mass_se);
  }
  EXPECT_EQ(a.top_configurations[0].mass, 1.0);
  EXPECT_GE(*a.top_configurations[0].mass_se, raw_top - 1.0);
  EXPECT_EQ(a.top_configurations[1].mass, 0.0);
  EXPECT_GE(*a.top_configurations[1].mass_se, 3.0 / 34.0);
  const std::string json = AnswerJson(a);
  EXPECT_EQ(json.find("\"mass\": -"), std::string::npos) << json;
  EXPECT_EQ(json.find("\"mass\": 1.0"), std::string::npos) << json;
  const std::string text = AnswerText(a);
  EXPECT_EQ(text.find("1.08"), std::string::npos) << text;
  EXPECT_EQ(text.find("-0.08"), std::string::npos) << text;
}

TEST(Answer, VerdictsAreFixedAtTheLevelAndFreeAtOneMinusIt) {
  EXPECT_EQ(kVerdictLevel, 0.95);
  EXPECT_EQ(VerdictOf(1.0), Verdict::kFixed);
  EXPECT_EQ(VerdictOf(0.95), Verdict::kFixed);
  EXPECT_EQ(VerdictOf(0.9499), Verdict::kNotDetermined);
  EXPECT_EQ(VerdictOf(0.5), Verdict::kNotDetermined);
  EXPECT_EQ(VerdictOf(0.0501), Verdict::kNotDetermined);
  EXPECT_EQ(VerdictOf(0.05), Verdict::kFree);
  EXPECT_EQ(VerdictOf(0.0), Verdict::kFree);
  EXPECT_EQ(VerdictOf(0.85, 0.8), Verdict::kFixed);
  EXPECT_STREQ(ToString(Verdict::kNotDetermined), "not determined");
}

// A run stopped during a wave: the answer is the last complete wave's and says so; with no
// complete wave at all, the incomplete one's, marked incomplete.
TEST(Answer, OfARunStoppedMidWaveIsTheLastCompleteWave) {
  testing::FakeRunOptions options;
  const RunMetadata m = testing::MakeFakeMetadata(options);
  RunHistory h = testing::MakeFakeHistory(options);
  h.waves.back().complete = false;
  h.waves.back().particles.resize(3);
  ComputeWaveStatistics(h.waves.back(), Estimator::kPaper);
  Answer a = SummariseAnswer(m, h);
  EXPECT_EQ(a.wave, options.waves - 1);
  EXPECT_EQ(a.waves, options.waves);
  EXPECT_TRUE(a.complete);
  EXPECT_EQ(a.bits[0].p_one, h.waves[options.waves - 2].marginals_paper[0]);
  EXPECT_NE(AnswerText(a).find("the numbers are wave 2's: wave 3 is incomplete"), std::string::npos)
      << AnswerText(a);

  h.waves.erase(h.waves.begin(), h.waves.end() - 1);
  a = SummariseAnswer(m, h);
  EXPECT_FALSE(a.complete);
  EXPECT_EQ(a.particles, 3);
  EXPECT_NE(AnswerJson(a).find("\"complete\": false"), std::string::npos);

  h.waves.clear();
  a = SummariseAnswer(m, h);
  EXPECT_EQ(a.wave, 0);
  EXPECT_TRUE(a.bits.empty());
  EXPECT_NE(AnswerText(a).find("none yet"), std::string::npos);
}

// Issue 35: a noise-aware run stopped early answers from a wave above T = 1, a tempered posterior;
// the answer said only which wave. It names each likelihood component's temperature (the
// thresholds' slots skip the indicators) in its text and JSON, and says tempered.
TEST(Answer, AWaveAboveTemperatureOneIsTempered) {
  testing::FakeRunOptions options;
  RunMetadata m = testing::MakeFakeMetadata(options);
  m.distance_components = {{"rise", ComponentKind::kIndicator, 1.0},
                           {"45cm/least_squares", ComponentKind::kNegLogLikelihood, 1.0},
                           {"area", ComponentKind::kThreshold, 1.0},
                           {"70cm/least_squares", ComponentKind::kNegLogLikelihood, 1.0}};
  RunHistory h = testing::MakeFakeHistory(options);
  for (WaveRecord& w : h.waves) w.thresholds = {3.9, 0.25, 19.0};
  Answer a = SummariseAnswer(m, h);
  ASSERT_EQ(a.temperatures.size(), 2u);
  EXPECT_EQ(a.temperatures[0].component, "45cm/least_squares");
  EXPECT_EQ(a.temperatures[1].temperature, 19.0);
  EXPECT_TRUE(a.tempered);
  const std::string text = AnswerText(a);
  EXPECT_NE(text.find("tempered: the likelihood's temperatures are 3.9 (45cm/least_squares), 19 "
                      "(70cm/least_squares)"),
            std::string::npos)
      << text;
  EXPECT_NE(AnswerJson(a).find("\"tempered\": true"), std::string::npos);
  EXPECT_NE(AnswerJson(a).find("{\"component\": \"70cm/least_squares\", \"temperature\": 19}"),
            std::string::npos)
      << AnswerJson(a);
  // At T = 1 it is the posterior, and nothing is said.
  h.waves.back().thresholds = {1.0, 0.25, 1.0};
  a = SummariseAnswer(m, h);
  EXPECT_FALSE(a.tempered);
  EXPECT_EQ(AnswerText(a).find("tempered"), std::string::npos);
  EXPECT_NE(AnswerJson(a).find("\"tempered\": false"), std::string::npos);
}

// The mode-loss diagnostic's flagged classes (WaveRecord::pattern_classes): in the answer, its
// JSON, its text (a warning line per wave) and the checks after sampling (summary.json, report).
TEST(Answer, FlaggedPatternClassesAreWarned) {
  testing::FakeRunOptions options;
  options.pattern_classes = true;
  const RunMetadata m = testing::MakeFakeMetadata(options);
  const RunHistory h = testing::MakeFakeHistory(options);
  const Answer a = SummariseAnswer(m, h);
  ASSERT_EQ(a.mode_loss.size(), 2u);  // waves 2 and 3, one flagged class each
  EXPECT_EQ(a.mode_loss[0].wave, 2);
  EXPECT_EQ(a.mode_loss[0].bits, PatternText(h.waves[1].pattern_classes[1].bits));
  EXPECT_EQ(a.mode_loss[0].mass, 0.05);
  EXPECT_EQ(a.mode_loss[0].proposal, 1e-6);
  const std::string text = AnswerText(a);
  EXPECT_NE(text.find("warning: wave 2 proposed pattern " + a.mode_loss[0].bits +
                      " (mass 0.05) with probability 1e-06; the posterior may have lost a mode\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("warning: wave 3 proposed pattern"), std::string::npos) << text;
  EXPECT_NE(AnswerJson(a).find("\"mode_loss\": [\n"), std::string::npos) << AnswerJson(a);
  EXPECT_NE(AnswerJson(a).find("\"mass\": 0.05, \"proposal\": 1e-06}"), std::string::npos)
      << AnswerJson(a);
  const FitChecks checks = ComputeFitChecks(m, h);
  int warned = 0;
  for (const CheckMessage& c : checks.after) warned += c.code == "mode_loss" ? 1 : 0;
  EXPECT_EQ(warned, 2);

  // Without flagged classes: no line, an empty list.
  const Answer quiet = SummariseAnswer(m, testing::MakeFakeHistory({}));
  EXPECT_EQ(AnswerText(quiet).find("lost a mode"), std::string::npos);
  EXPECT_NE(AnswerJson(quiet).find("\"mode_loss\": [],"), std::string::npos);
}

// The sensor's clamps: 18 per edge over 90 cm (the 45 cm example's config); clamp 1 is the first
// 5 cm of edge 1, clamp 19 the first 5 cm of edge 2 (config_simulator.cpp names them in that
// order). The terminal shows the two edges side by side, within 80 columns.
TEST(Answer, PlacesTheSensorsClampsFromTheRunsConfig) {
  testing::TempFolder dir("answer-positions");
  testing::FakeRunOptions options;
  RunMetadata m = testing::MakeFakeMetadata(options);
  const fs::path example = fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm";
  std::ifstream in(example / "least_squares.toml");
  std::stringstream text;
  text << in.rdbuf();
  m.config_text = text.str();
  m.config_path = (example / "least_squares.toml").string();
  // A point the Gaussian extension would add toward the load: stored with the measured ones, but
  // not scanned (the strip's scan line stays within the data window, 48-80 cm).
  m.measured.positions.insert(m.measured.positions.begin(), 0.42);
  m.measured.values.insert(m.measured.values.begin(), 0.5);
  const std::string path = dir / "RUN.db";
  {
    HistoryStore store = HistoryStore::Create(path, m);
    const RunHistory h = testing::MakeFakeHistory(options);
    for (const WaveRecord& wave : h.waves) testing::RecordWave(store, wave, 10);
    store.Finish(h.summary);
  }
  const Answer a = services::ReadAnswer(path);
  ASSERT_EQ(a.bits.size(), 36u);
  const auto expect = [&](int number, int edge, double start, double end, const char* shown_as) {
    const AnswerBit& b = a.bits[static_cast<std::size_t>(number - 1)];
    EXPECT_EQ(b.name, "clamp " + std::to_string(number));
    ASSERT_TRUE(b.position) << number;
    EXPECT_EQ(b.position->edge, edge) << number;
    EXPECT_NEAR(b.position->start_m, start, 1e-12) << number;
    EXPECT_NEAR(b.position->end_m, end, 1e-12) << number;
    EXPECT_EQ(b.position->Text(), shown_as);
  };
  expect(1, 1, 0.0, 0.05, "edge 1, 0-5 cm");
  expect(10, 1, 0.45, 0.50, "edge 1, 45-50 cm");
  expect(18, 1, 0.85, 0.90, "edge 1, 85-90 cm");
  expect(19, 2, 0.0, 0.05, "edge 2, 0-5 cm");
  expect(36, 2, 0.85, 0.90, "edge 2, 85-90 cm");

  const std::string shown = AnswerText(a);
  EXPECT_NE(shown.find("edge 1 (y = 0)"), std::string::npos) << shown;
  std::istringstream lines(shown);
  int rows = 0;
  for (std::string line; std::getline(lines, line); ++rows) {
    std::size_t chars = 0;
    for (char c : line) chars += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    EXPECT_LE(chars, 80u) << line;
  }
  EXPECT_LE(rows, 40) << shown;  // one screen
  // Clamp 1 and clamp 19 share the first row of the table.
  EXPECT_NE(shown.find("\n     1   0-5  "), std::string::npos) << shown;
  EXPECT_NE(shown.find("   19   0-5  "), std::string::npos) << shown;

  // The strip's layout in summary.json (issue 34): the example's plate, its load at 45 cm on the
  // centreline and its scan over the data window on the centreline.
  services::ExportHistory(path, dir / "export", false, /*netcdf=*/false);
  std::ifstream json(fs::path(dir / "export") / "summary.json");
  std::stringstream summary;
  summary << json.rdbuf();
  const std::string exported = summary.str();
  EXPECT_NE(
      exported.find("\"strip\": {\"length_m\": 0.9, \"width_m\": 0.04, \"clamps_per_edge\": 18, "
                    "\"experiments\": [\n    {\"name\": \"\", \"load_x_m\": 0.45, "
                    "\"load_y_m\": 0.02, \"scan_from_m\": "),
      std::string::npos)
      << exported;
  const auto number_after = [&exported](const std::string& key) {
    const std::size_t at = exported.find("\"" + key + "\": ", exported.find("\"strip\": "));
    return at == std::string::npos ? -1.0 : std::stod(exported.substr(at + key.size() + 4));
  };
  EXPECT_NEAR(number_after("scan_from_m"), 0.48, 1e-12);  // not the extension's 0.42
  EXPECT_NEAR(number_after("scan_to_m"), 0.80, 1e-12);
  EXPECT_NEAR(number_after("scan_y_m"), 0.02, 1e-12);
}

// The strip for a terminal (export/strip.hpp): a hand-made answer on a strip of 10 sections per
// edge over 50 cm, 3 cm wide (not the default 18 over 90 cm), drawn at 80 columns without colour.
// Each section's symbol sits in its own columns (to scale: 7 columns of 5 cm each), the load and
// scan line where the layout puts them, and the verdict line lists the groups.
Answer StripAnswer(int per_edge) {
  Answer a;
  a.wave = 1;
  a.waves = 1;
  a.complete = true;
  for (int k = 1; k <= 2 * per_edge; ++k) {
    AnswerBit bit;
    bit.number = k;
    bit.name = "clamp " + std::to_string(k);
    // Clamps 3 and 13 fixed, 4 and 14 free, 5 at P = 0.62, the others at P = 0.31.
    bit.p_one = k % per_edge == 3 ? 0.99 : k % per_edge == 4 ? 0.01 : k == 5 ? 0.62 : 0.31;
    bit.verdict = VerdictOf(bit.p_one);
    a.bits.push_back(bit);
  }
  return a;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(Strip, DrawsTheStripToScaleIn80ColumnsWithoutColour) {
  StripLayout strip;
  strip.length_m = 0.50;
  strip.width_m = 0.03;
  strip.clamps_per_edge = 10;
  // A load at 22 cm on the centreline scanned over 30-45 cm along edge 1 (y = 0).
  strip.experiments.push_back({"near", 0.22, 0.015, 0.30, 0.45, 0.0});
  const std::string shown = StripText(StripAnswer(10), strip, TextStyle{80, false, false});
  EXPECT_EQ(shown.find('\033'), std::string::npos) << shown;
  const std::vector<std::string> lines = Lines(shown);
  for (const std::string& line : lines) EXPECT_LE(line.size(), 80u) << line;
  const auto row = [&](const std::string& head) {
    for (const std::string& line : lines) {
      if (line.rfind(head, 0) == 0) return line;
    }
    ADD_FAILURE() << "no line starting with '" << head << "' in\n" << shown;
    return std::string();
  };
  // 7 label columns, "|", then 10 sections of 7 columns: 6 symbols and a "|".
  const std::string edge1 = row("edge 1 |");
  const std::string edge2 = row("edge 2 |");
  ASSERT_EQ(edge1.size(), 8u + 70u) << shown;
  const auto section = [](const std::string& line, int s) {
    return line.substr(8 + 7 * static_cast<std::size_t>(s), 7);
  };
  EXPECT_EQ(section(edge1, 2), "######|");  // clamp 3: fixed
  EXPECT_EQ(section(edge1, 3), "......|");  // clamp 4: free
  EXPECT_EQ(section(edge1, 4), "   6  |");  // clamp 5: P = 0.62, in tenths
  EXPECT_EQ(section(edge1, 0), "   3  |");
  EXPECT_EQ(section(edge2, 2), "######|");  // clamp 13
  EXPECT_EQ(section(edge2, 3), "......|");  // clamp 14
  // Edge 2 above edge 1, the clamp numbers outside them, the inside between them.
  const auto at = [&](const std::string& line) {
    return std::find(lines.begin(), lines.end(), line) - lines.begin();
  };
  EXPECT_EQ(at(edge1) - at(edge2), 4) << shown;
  EXPECT_NE(lines[static_cast<std::size_t>(at(edge2) - 1)].find("    11"), std::string::npos);
  EXPECT_NE(lines[static_cast<std::size_t>(at(edge1) + 1)].find("     1"), std::string::npos);
  // The load: column 8 + floor(22/50 * 70) = 38 of the middle row; the scan along the bottom one
  // from 8 + 42 to 8 + 63 (the column of 45 cm).
  const std::string middle = lines[static_cast<std::size_t>(at(edge2) + 2)];
  const std::string bottom = lines[static_cast<std::size_t>(at(edge2) + 3)];
  EXPECT_EQ(middle.find('1'), 38u) << shown;
  EXPECT_EQ(bottom.find('-'), 50u) << shown;
  EXPECT_EQ(bottom.rfind('-'), 71u) << shown;
  // The axis: 0 under the strip's left end, 50 (cm) at its right end.
  const std::string axis = row("x (cm)");
  EXPECT_EQ(axis.find(" 0 "), 7u - 1u) << axis;
  EXPECT_EQ(axis.substr(axis.size() - 2), "50") << axis;
  EXPECT_NE(shown.find(" 1 near: load at 22 cm, 15 mm from edge 1; scan 30-45 cm at 0 mm\n"),
            std::string::npos)
      << shown;
  EXPECT_NE(shown.find("verdict: fixed: 3, 13; free: 4, 14; not determined: 16 clamps\n"),
            std::string::npos)
      << shown;
}

// With colour, the same picture: each section's background follows its P(fixed); without the
// escapes the text is the colourless one. The default 18 sections per edge fill 80 columns.
TEST(Strip, ColoursOnlyAddToTheSymbols) {
  StripLayout strip;
  strip.length_m = 0.90;
  strip.width_m = 0.04;
  strip.clamps_per_edge = 18;
  strip.experiments.push_back({"", 0.45, 0.02, 0.48, 0.80, 0.02});
  const Answer a = StripAnswer(18);
  const std::string plain = StripText(a, strip, TextStyle{80, false, false});
  for (const std::string& line : Lines(plain)) EXPECT_LE(line.size(), 80u) << line;
  for (bool many : {false, true}) {
    const std::string coloured = StripText(a, strip, TextStyle{80, true, many});
    std::string stripped;
    for (std::size_t k = 0; k < coloured.size(); ++k) {
      if (coloured[k] == '\033') {
        k = coloured.find('m', k);
      } else {
        stripped += coloured[k];
      }
    }
    EXPECT_EQ(stripped, plain);
    // Fixed (clamp 3, P = 0.99) dark green with white text, not determined (P = 0.31) pale,
    // with black text: the page's colours, rgb(29, 121, 57) and rgb(175, 205, 183), at the nearest
    // levels of the 256-colour cube, (0, 2, 1) and (3, 4, 3).
    const std::string fixed = many ? "\033[48;5;29m\033[38;5;15m" : "\033[42;30m";
    const std::string open = many ? "\033[48;5;151m\033[38;5;16m" : "\033[43;30m";
    EXPECT_NE(coloured.find(fixed + "###"), std::string::npos) << coloured;
    EXPECT_NE(coloured.find(open + " 3 "), std::string::npos) << coloured;
  }
  // The sections do not fit: a note, and still the verdicts.
  strip.clamps_per_edge = 100;
  const std::string crowded = StripText(StripAnswer(100), strip);
  EXPECT_NE(crowded.find("do not fit in 80 columns"), std::string::npos) << crowded;
  EXPECT_NE(crowded.find("verdict: fixed:"), std::string::npos) << crowded;
  // No strip for an answer whose bits are not the strip's clamps.
  EXPECT_EQ(StripText(StripAnswer(10), strip), "");
}

// The terminal's style: colour only on a terminal (a pseudo-terminal here) whose TERM is set and
// not "dumb", and not with NO_COLOR set and not empty; 256 colours when TERM says so.
TEST(Strip, ColourOnlyOnATerminalThatHasItAndNoColorHonoured) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const int terminal = ::open(::ptsname(master), O_RDWR | O_NOCTTY);
  ASSERT_GE(terminal, 0);
  const int file = ::open("/dev/null", O_WRONLY);
  ASSERT_GE(file, 0);
  const auto saved = [](const char* name) -> std::optional<std::string> {
    const char* value = std::getenv(name);
    return value ? std::optional<std::string>(value) : std::nullopt;
  };
  const auto term = saved("TERM"), no_colour = saved("NO_COLOR"), colour_term = saved("COLORTERM");
  const auto set = [](const char* name, const char* value) {
    value ? ::setenv(name, value, 1) : ::unsetenv(name);
  };
  const auto style = [&](const char* t, const char* n, int fd) {
    set("TERM", t);
    set("NO_COLOR", n);
    return TerminalStyle(fd);
  };
  set("COLORTERM", nullptr);
  EXPECT_TRUE(style("xterm-256color", nullptr, terminal).colour);
  EXPECT_TRUE(style("xterm-256color", nullptr, terminal).colour256);
  EXPECT_TRUE(style("xterm", nullptr, terminal).colour);
  EXPECT_FALSE(style("xterm", nullptr, terminal).colour256);
  EXPECT_TRUE(style("xterm", "", terminal).colour);  // empty: not set (no-color.org)
  EXPECT_FALSE(style("xterm-256color", "1", terminal).colour);
  EXPECT_FALSE(style("dumb", nullptr, terminal).colour);
  EXPECT_FALSE(style(nullptr, nullptr, terminal).colour);
  EXPECT_FALSE(style("xterm-256color", nullptr, file).colour);  // not a terminal
  EXPECT_EQ(style("xterm", nullptr, terminal).columns, 80);
  set("TERM", term ? term->c_str() : nullptr);
  set("NO_COLOR", no_colour ? no_colour->c_str() : nullptr);
  set("COLORTERM", colour_term ? colour_term->c_str() : nullptr);
  ::close(file);
  ::close(terminal);
  ::close(master);
}

}  // namespace
}  // namespace combabc
