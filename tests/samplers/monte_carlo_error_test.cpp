// The delta-method standard errors and per-quantity ESS of samplers/monte_carlo_error.hpp against
// values computed by hand.
#include "combabc/samplers/monte_carlo_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

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
  for (std::size_t i = 0; i < weights.size(); ++i) {
    Particle p;
    p.weight = weights[i];
    p.theta.bits = bits[i];
    p.theta.reals = {reals[i]};
    wave.particles.push_back(p);
  }
  const WaveErrors e = WaveMonteCarloErrors(wave);
  ASSERT_EQ(e.bits.size(), 2u);
  // Bit 1: p = 0.4, deviations 0.6, -0.4, 0.6, -0.4:
  // se^2 = 0.01 * 0.36 + 0.04 * 0.16 + 0.09 * 0.36 + 0.16 * 0.16 = 0.068, ESS = 0.24 / 0.068.
  EXPECT_NEAR(e.bits[0].value, 0.4, 1e-15);
  EXPECT_NEAR(e.bits[0].se, std::sqrt(0.068), 1e-15);
  EXPECT_NEAR(e.bits[0].ess, 0.24 / 0.068, 1e-12);
  // Bit 2 is 1 in every particle: no error, and it does not set the bits' ESS.
  EXPECT_EQ(e.bits[1].se, 0.0);
  ASSERT_TRUE(e.bits_ess);
  EXPECT_DOUBLE_EQ(*e.bits_ess, e.bits[0].ess);
  ASSERT_EQ(e.real_means.size(), 1u);
  const WeightedMoment mean = WeightedMean(weights, reals);
  EXPECT_DOUBLE_EQ(e.real_means[0].se, mean.se);
  EXPECT_DOUBLE_EQ(e.real_sds[0].se, WeightedSd(weights, reals).se);
  // No particles: no estimates, no bits' ESS.
  EXPECT_FALSE(WaveMonteCarloErrors(WaveRecord{}).bits_ess);
}

}  // namespace
}  // namespace combabc
