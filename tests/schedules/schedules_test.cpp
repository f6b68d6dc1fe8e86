#include <gtest/gtest.h>

#include <cmath>

#include "combabc/schedules/tempering_schedule.hpp"
#include "combabc/schedules/threshold_schedule.hpp"

namespace combabc {
namespace {

TEST(EmpiricalQuantile, IsTheCeilAlphaNthOrderStatistic) {
  const std::vector<double> v = {5, 1, 4, 2, 3};
  EXPECT_EQ(EmpiricalQuantile(v, 0.5), 3);  // ceil(2.5) = 3rd smallest
  EXPECT_EQ(EmpiricalQuantile(v, 0.2), 1);
  EXPECT_EQ(EmpiricalQuantile(v, 1.0), 5);
  EXPECT_EQ(EmpiricalQuantile(v, 0.21), 2);
}

TEST(ThresholdSchedule, QuantileStartsAtInitialAndFloorsAtTarget) {
  ThresholdSchedule s;
  s.quantile = 0.5;
  s.target = 2.5;
  EXPECT_TRUE(std::isinf(s.ThresholdFor(0, {})));
  const std::vector<double> prev = {1, 2, 3, 4, 5, 6};
  EXPECT_EQ(s.ThresholdFor(1, {.distances = prev}), 3);
  const std::vector<double> low = {0, 1, 2, 2};
  EXPECT_EQ(s.ThresholdFor(2, {.distances = low}), 2.5);
  EXPECT_TRUE(s.IsFinal(2, 2.5));
  EXPECT_FALSE(s.IsFinal(1, 3));
}

TEST(ThresholdSchedule, WeightedQuantileUsesTheImportanceWeights) {
  ThresholdSchedule s;
  s.quantile = 0.5;
  const std::vector<double> d = {1, 2, 3, 4};
  const std::vector<double> w = {0.1, 0.1, 0.1, 0.7};
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .importance = w}), 2);  // unweighted: ignored
  s.weighted = true;
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .importance = w}), 4);
  // With a multi-fidelity run's counts too: the weight is count x importance.
  const std::vector<double> counts = {10, 1, 1, 1};
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .counts = counts, .importance = w}), 1);
}

TEST(ThresholdSchedule, AcceptanceRateScalesTheQuantileByThePreviousRate) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kAcceptance;
  s.acceptance_rate = 0.1;
  std::vector<double> d(10);
  for (int i = 0; i < 10; ++i) d[static_cast<std::size_t>(i)] = i + 1;  // 1..10
  // Previous rate 0.4: a fraction 0.1 / 0.4 = 0.25 of the accepted within eps -> the 3rd of 10.
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .acceptance_rate = 0.4}), 3);
  // Previous rate 0.2: half of them -> the 5th.
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .acceptance_rate = 0.2}), 5);
  // At or below the target rate: the largest accepted distance, no tighter.
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .acceptance_rate = 0.05}), 10);
  s.target = 4;
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .acceptance_rate = 0.4}), 4);
  EXPECT_TRUE(std::isinf(s.ThresholdFor(0, {})));
}

TEST(ThresholdSchedule, EssKeepsAFractionOfTheEffectiveSampleSize) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kEss;
  s.ess_fraction = 0.5;
  // Equal weights: the ESS within eps is the count, so half the particles: the 4th of 8.
  const std::vector<double> d = {8, 7, 6, 5, 4, 3, 2, 1};
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d}), 4);
  // Weights 4 on distance 1, 1 on the rest: ESS(all) = 11^2 / 23 = 5.26; the target 2.63 needs
  // ESS(1..k) = (4 + k - 1)^2 / (16 + k - 1) >= 2.63: k = 1 gives 1, k = 2 gives 25 / 17 = 1.47,
  // k = 3: 36 / 18 = 2, k = 4: 49 / 19 = 2.58, k = 5: 64 / 20 = 3.2 -> distance 5.
  const std::vector<double> w = {1, 1, 1, 1, 1, 1, 1, 4};
  EXPECT_EQ(s.ThresholdFor(1, {.distances = d, .importance = w}), 5);
  // Ties enter together.
  const std::vector<double> tied = {1, 1, 1, 1, 2, 2, 2, 2};
  EXPECT_EQ(EssThreshold(tied, std::vector<double>(8, 1.0), 0.25), 1);
  EXPECT_EQ(EssThreshold(tied, std::vector<double>(8, 1.0), 0.75), 2);
}

TEST(ThresholdSchedule, NewKindsValidateTheirParameters) {
  ThresholdSchedule s;
  std::string why;
  s.kind = ThresholdKind::kAcceptance;
  s.acceptance_rate = 0.0;
  EXPECT_FALSE(s.IsValid("s", 3, &why));
  EXPECT_EQ(why, "s.acceptance_rate = 0.000000; must be in (0, 1]");
  s.kind = ThresholdKind::kEss;
  s.ess_fraction = 1.0;
  EXPECT_FALSE(s.IsValid("s", 3, &why));
  EXPECT_EQ(why, "s.ess_fraction = 1.000000; must be in (0, 1)");
  s.ess_fraction = 0.5;
  s.weighted = true;
  EXPECT_FALSE(s.IsValid("s", 3, &why));
  EXPECT_EQ(why, "s.weighted = true; only the quantile schedule takes importance weights");
  s.weighted = false;
  EXPECT_TRUE(s.IsValid("s", 3, &why)) << why;
}

TEST(ThresholdSchedule, ListIsFinalAtItsLastWave) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = {3, 2, 1};
  std::string why;
  EXPECT_TRUE(s.IsValid("s", 3, &why)) << why;
  EXPECT_EQ(s.ThresholdFor(1, {}), 2);
  EXPECT_FALSE(s.IsFinal(1, 2));
  EXPECT_TRUE(s.IsFinal(2, 1));
  s.values = {3, 4, 1};
  EXPECT_FALSE(s.IsValid("s", 3, &why));
  EXPECT_EQ(why, "s.values[1] = 4.000000 > values[0]; thresholds must not increase (Eq. 1)");
}

// Eq. 3 for one bit, computed independently: q ∝ q~^(1-phi) p^phi over {0, 1}.
double Eq3(double p_hat, double prior, double phi) {
  const double a = std::pow(p_hat, 1 - phi) * std::pow(prior, phi);
  const double b = std::pow(1 - p_hat, 1 - phi) * std::pow(1 - prior, phi);
  return a / (a + b);
}

TEST(TemperedProbability, GeometricMatchesEq3AndItsLimits) {
  for (double p_hat : {0.1, 0.5, 0.93}) {
    for (double prior : {0.2, 0.5, 0.7}) {
      for (double phi : {0.0, 0.25, 0.6, 1.0}) {
        EXPECT_NEAR(TemperedProbability(p_hat, prior, phi, TemperingForm::kGeometric),
                    Eq3(p_hat, prior, phi),
                    1e-15);
      }
      EXPECT_NEAR(TemperedProbability(p_hat, prior, 0.0, TemperingForm::kGeometric), p_hat, 1e-15);
      EXPECT_NEAR(TemperedProbability(p_hat, prior, 1.0, TemperingForm::kGeometric), prior, 1e-15);
    }
  }
  // Exactly as Eq. 3 says: a stuck bit stays stuck for phi < 1 and returns to the prior at 1.
  EXPECT_EQ(TemperedProbability(0.0, 0.5, 0.5, TemperingForm::kGeometric), 0.0);
  EXPECT_EQ(TemperedProbability(1.0, 0.5, 0.5, TemperingForm::kGeometric), 1.0);
  EXPECT_EQ(TemperedProbability(0.0, 0.3, 1.0, TemperingForm::kGeometric), 0.3);
  // The mixture extension unsticks it: (1 - phi) * 0 + phi * prior.
  EXPECT_NEAR(TemperedProbability(0.0, 0.5, 0.4, TemperingForm::kMixture), 0.2, 1e-15);
}

TEST(TemperingSchedule, LinearFallsFromPhi0ToZeroOverThePlannedWaves) {
  TemperingSchedule s;
  s.kind = TemperingKind::kLinear;
  s.phi0 = 0.6;
  EXPECT_EQ(s.Phi(0, 5), 1.0);  // wave 0 is the prior
  EXPECT_NEAR(s.Phi(1, 5), 0.6, 1e-15);
  EXPECT_NEAR(s.Phi(2, 5), 0.4, 1e-15);
  EXPECT_NEAR(s.Phi(3, 5), 0.2, 1e-15);
  EXPECT_NEAR(s.Phi(4, 5), 0.0, 1e-15);
  s.kind = TemperingKind::kNone;
  EXPECT_EQ(s.Phi(3, 5), 0.0);
  s.kind = TemperingKind::kList;
  s.values = {0.9, 0.1};
  EXPECT_EQ(s.Phi(2, 3), 0.1);
  EXPECT_EQ(ParseEnum<TemperingKind>("linear"), TemperingKind::kLinear);
  EXPECT_EQ(ParseEnum<TemperingKind>("Linear"), std::nullopt);
  EXPECT_EQ(ParseEnum<TemperingForm>(ToString(TemperingForm::kMixture)), TemperingForm::kMixture);
}

}  // namespace
}  // namespace combabc
