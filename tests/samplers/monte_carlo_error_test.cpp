// The delta-method standard errors and per-quantity ESS of samplers/monte_carlo_error.hpp against
// values computed by hand.
#include "combabc/samplers/monte_carlo_error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

TEST(MonteCarloError, AWeightedMeanHasTheDeltaMethodError) {
  // w = 1, 1, 2 (sum 4), f = 0, 3, 6: mean 15 / 4 = 3.75, deviations -3.75, -0.75, 2.25;
  // sum w^2 d^2 = 14.0625 + 0.5625 + 4 * 5.0625 = 34.875, se = sqrt(34.875) / 4;
  // Var_w = (14.0625 + 0.5625 + 2 * 5.0625) / 4 = 6.1875, ESS = 6.1875 / se^2.
  const WeightedMoment m = WeightedMean(std::vector<double>{1, 1, 2}, std::vector<double>{0, 3, 6});
  EXPECT_DOUBLE_EQ(m.value, 3.75);
  EXPECT_NEAR(m.se, std::sqrt(34.875) / 4.0, 1e-15);
  EXPECT_NEAR(m.ess, 6.1875 * 16.0 / 34.875, 1e-12);
  // Above the weights' ESS, 16 / 6: the heaviest particle is not the farthest from the mean.
  EXPECT_GT(m.ess, 16.0 / 6.0);
}

TEST(MonteCarloError, EqualWeightsGiveTheTextbookErrors) {
  // f = 1, 2, 3, 4: mean 2.5, population variance 1.25, se = sqrt(1.25 / 4), ESS = n = 4.
  const std::vector<double> w(4, 0.25);
  const std::vector<double> f = {1, 2, 3, 4};
  const WeightedMoment mean = WeightedMean(w, f);
  EXPECT_DOUBLE_EQ(mean.value, 2.5);
  EXPECT_NEAR(mean.se, std::sqrt(1.25 / 4.0), 1e-15);
  EXPECT_NEAR(mean.ess, 4.0, 1e-12);
  // The sd: influence terms d^2 - var = 1, -1, -1, 1, so se(var) = sqrt(4) / 4 = 0.5 and
  // se(sd) = 0.5 / (2 sqrt(1.25)); their own ESS is Var(psi) / se(var)^2 = 1 / 0.25 = 4.
  const WeightedMoment sd = WeightedSd(w, f);
  EXPECT_NEAR(sd.value, std::sqrt(1.25), 1e-15);
  EXPECT_NEAR(sd.se, 0.5 / (2.0 * std::sqrt(1.25)), 1e-15);
  EXPECT_NEAR(sd.ess, 4.0, 1e-12);
  // A proportion: sqrt(p (1 - p) / n).
  const WeightedMoment p = WeightedMean(w, std::vector<double>{1, 0, 0, 0});
  EXPECT_NEAR(p.se, std::sqrt(0.25 * 0.75 / 4.0), 1e-15);
}

TEST(MonteCarloError, SignedWeightsAreNormalisedByTheirSignedSum) {
  // w = 2, -1, 1 (sum 2), f = 1, 1, 0: mean 1 / 2; d = 0.5, 0.5, -0.5;
  // sum w^2 d^2 = (4 + 1 + 1) / 4 = 1.5, se = sqrt(1.5) / 2.
  const WeightedMoment m =
      WeightedMean(std::vector<double>{2, -1, 1}, std::vector<double>{1, 1, 0});
  EXPECT_DOUBLE_EQ(m.value, 0.5);
  EXPECT_NEAR(m.se, std::sqrt(1.5) / 2.0, 1e-15);
  // Weights that cancel have no estimate: an infinite error.
  EXPECT_TRUE(std::isinf(WeightedMean(std::vector<double>{1, -1}, std::vector<double>{0, 1}).se));
}

TEST(MonteCarloError, AConstantQuantityHasNoErrorAndTheWeightsEss) {
  const std::vector<double> w = {1, 2, 3, 4};  // (sum w)^2 / sum w^2 = 100 / 30
  const WeightedMoment m = WeightedMean(w, std::vector<double>(4, 2.0));
  EXPECT_EQ(m.se, 0.0);
  EXPECT_NEAR(m.ess, 100.0 / 30.0, 1e-12);
  const WeightedMoment sd = WeightedSd(w, std::vector<double>(4, 2.0));
  EXPECT_EQ(sd.value, 0.0);
  EXPECT_EQ(sd.se, 0.0);
}

TEST(MonteCarloError, AWavesErrorsAreEachQuantitysUnderTheStoredWeights) {
  WaveRecord wave;
  const std::vector<double> weights = {0.1, 0.2, 0.3, 0.4};
  const std::vector<std::vector<std::uint8_t>> bits = {{1, 1}, {0, 1}, {1, 1}, {0, 1}};
  const std::vector<double> reals = {-1.0, 0.5, 2.0, 3.0};
  // 25 copies of the four particles (weights / 25): the sums below shrink by 25, and the weights'
  // ESS is 25 / 0.3 (enough that the rule of three's floor, 3 / ESS = 0.036, does not hide the
  // delta method's error of bit 1).
  constexpr int kCopies = 25;
  std::vector<double> all_weights, all_reals;
  for (int copy = 0; copy < kCopies; ++copy) {
    for (std::size_t i = 0; i < weights.size(); ++i) {
      Particle p;
      p.weight = weights[i] / kCopies;
      p.theta.bits = bits[i];
      p.theta.reals = {reals[i]};
      wave.particles.push_back(p);
      all_weights.push_back(p.weight);
      all_reals.push_back(reals[i]);
    }
  }
  const WaveErrors e = WaveMonteCarloErrors(wave);
  ASSERT_EQ(e.bits.size(), 2u);
  // Bit 1: p = 0.4, deviations 0.6, -0.4, 0.6, -0.4:
  // se^2 = (0.01 * 0.36 + 0.04 * 0.16 + 0.09 * 0.36 + 0.16 * 0.16) / 25 = 0.068 / 25,
  // ESS = 0.24 / se^2.
  EXPECT_NEAR(e.bits[0].value, 0.4, 1e-15);
  EXPECT_NEAR(e.bits[0].se, std::sqrt(0.068 / kCopies), 1e-15);
  EXPECT_NEAR(e.bits[0].ess, 0.24 * kCopies / 0.068, 1e-9);
  // Bit 2 is 1 in every particle: the delta method sees no error, the rule of three's floor
  // 3 / ESS does (100 particles do not show that P = 1 exactly); it does not set the bits' ESS.
  EXPECT_NEAR(e.bits[1].se, 3.0 * 0.3 / kCopies, 1e-12);
  ASSERT_TRUE(e.bits_ess);
  EXPECT_DOUBLE_EQ(*e.bits_ess, e.bits[0].ess);
  // A bit its prior fixes (P(bit 2 = 1) = 1) is known: error 0.
  EXPECT_EQ(WaveMonteCarloErrors(wave, std::vector<double>{0.5, 1.0}).bits[1].se, 0.0);
  ASSERT_EQ(e.real_means.size(), 1u);
  EXPECT_DOUBLE_EQ(e.real_means[0].se, WeightedMean(all_weights, all_reals).se);
  EXPECT_DOUBLE_EQ(e.real_sds[0].se, WeightedSd(all_weights, all_reals).se);
  // No particles: no estimates, no bits' ESS.
  EXPECT_FALSE(WaveMonteCarloErrors(WaveRecord{}).bits_ess);
}

TEST(MonteCarloError, AProbabilityOfZeroOrOneHasTheRuleOfThreesError) {
  // 50 equal weights, none has the quantity: the delta method says 0 +- 0; the floor 3 / 50.
  const std::vector<double> w(50, 1.0);
  const std::vector<double> none(50, 0.0);
  EXPECT_EQ(WeightedMean(w, none).se, 0.0);
  const WeightedMoment zero = WeightedProbability(w, none);
  EXPECT_EQ(zero.value, 0.0);
  EXPECT_DOUBLE_EQ(zero.se, 3.0 / 50.0);
  EXPECT_DOUBLE_EQ(WeightedProbability(w, std::vector<double>(50, 1.0)).se, 3.0 / 50.0);
  // Common enough (25 of 50), the delta method's error stands: sqrt(0.25 / 50) > 3 / 50.
  std::vector<double> half(50, 0.0);
  for (std::size_t i = 0; i < 25; ++i) half[i] = 1.0;
  EXPECT_DOUBLE_EQ(WeightedProbability(w, half).se, WeightedMean(w, half).se);
  // Near the edge, the interval reaches 3 / 50 from it: 2 of 50 (p = 0.04) get at least
  // 0.06 - 0.04.
  std::vector<double> two(50, 0.0);
  two[0] = two[1] = 1.0;
  const WeightedMoment rare = WeightedProbability(w, two);
  EXPECT_GT(WeightedMean(w, two).se, 0.02);  // sqrt(0.04 * 0.96 / 50) = 0.028: the delta method's
  EXPECT_DOUBLE_EQ(rare.se, WeightedMean(w, two).se);
  // A multi-fidelity wave counts in its heaviest particles: 49 of weight 1 and one of 5 (a
  // continued cheap rejection, 1 / eta = 5): sum w / max w = 54 / 5, so a quantity none has gets
  // 3 * 5 / 54, not 3 / ESS (ESS = 54^2 / 74 = 39).
  std::vector<double> heavy(50, 1.0);
  heavy[49] = 5.0;
  EXPECT_NEAR(WeightedProbability(heavy, none).se, 3.0 * 74.0 / (54.0 * 54.0), 1e-12);
  EXPECT_NEAR(WeightedProbability(heavy, none, true).se, 3.0 * 5.0 / 54.0, 1e-12);
  // Few particles: the floor is at most 0.5, the largest sd of a probability.
  EXPECT_DOUBLE_EQ(WeightedProbability(std::vector<double>{1, 1}, std::vector<double>{0, 0}).se,
                   0.5);
}

TEST(MonteCarloError, ASignedProbabilityIsClampedAndItsErrorCoversTheRawEstimate) {
  // w = 3, 3, -2 (sum 4), f = 1, 1, 0: raw 6 / 4 = 1.5; clamped to 1 with an error >= 0.5.
  // The signed weights' ESS 16 / 22 is below 6: the floor is 0.5 as well.
  const std::vector<double> w = {3, 3, -2};
  const std::vector<double> f = {1, 1, 0};
  EXPECT_DOUBLE_EQ(WeightedMean(w, f).value, 1.5);
  const WeightedMoment p = WeightedProbability(w, f);
  EXPECT_EQ(p.value, 1.0);
  EXPECT_GE(p.se, 0.5);
  EXPECT_DOUBLE_EQ(p.se, std::max(WeightedMean(w, f).se, 0.5));
  // 100 weights of 1 and one of -0.5 on the same particle set: the raw estimate 1.005 is
  // clamped to 1 and the floor 3 / ESS covers the 0.005.
  std::vector<double> many(100, 1.0), ones(100, 1.0);
  many.push_back(-0.5);
  ones.push_back(0.0);
  const WeightedMoment q = WeightedProbability(many, ones);
  EXPECT_EQ(q.value, 1.0);
  EXPECT_GE(q.se, WeightedMean(many, ones).value - 1.0);
  // Weights that cancel: still an infinite error.
  EXPECT_TRUE(
      std::isinf(WeightedProbability(std::vector<double>{1, -1}, std::vector<double>{0, 1}).se));
}

// An exact-known toy (3 independent bits, the distance blind to bit 1, whose posterior is
// therefore its prior, 0.01): over a few seeds a run of 100 particles sees no particle with bit
// 1 and estimates P = 0. The delta method calls that 0 +- 0; the reported error must not be 0,
// and must cover the exact 0.01 within 2 standard errors.
TEST(MonteCarloError, ARareBitEstimatedAsZeroGetsAnErrorCoveringItsExactProbability) {
  constexpr double kRare = 0.01;
  BinarySpaceOptions so;
  so.dimension = 3;
  so.prior_one = {kRare, 0.5, 0.5};
  const ParameterSpace space{BinarySpace(so)};
  const testing::IdentitySimulator sim(3);
  const testing::WeightedL1Distance dist({0, 1, 0}, {0, 1, 1});
  int zeros = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SmcOptions o;
    o.num_waves = 2;
    o.accepted_per_wave = 100;
    o.seed = seed;
    o.threads = 1;
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = {1.0, 0.0};
    o.thresholds = {s};
    const RunHistory h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    const WaveRecord& last = h.waves.back();
    ASSERT_EQ(last.particles.size(), 100u);
    const WaveErrors e = WaveMonteCarloErrors(last);
    if (e.bits[0].value != 0.0) continue;
    ++zeros;
    std::vector<double> w, none;
    for (const Particle& p : last.particles) {
      w.push_back(p.weight);
      none.push_back(0.0);
    }
    EXPECT_EQ(WeightedMean(w, none).se, 0.0);  // what the delta method alone reports
    EXPECT_GT(e.bits[0].se, 0.0) << "seed " << seed;
    EXPECT_GE(2.0 * e.bits[0].se, kRare) << "seed " << seed;
  }
  // (1 - 0.01)^100 = 0.37 a seed: the test needs at least one of its seeds to estimate 0.
  EXPECT_GT(zeros, 0);
}

}  // namespace
}  // namespace combabc
