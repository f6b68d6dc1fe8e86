// Enumeration as the reference for ABC-SMC: at the same final threshold, the importance estimator
// of combinatorial ABC-SMC must agree with the enumerated marginals within 5 Monte-Carlo standard
// errors (from the final wave's ESS). Fixed seed: deterministic, and at 5 sigma per bit a
// correct sampler would fail for essentially no seed.
#include <gtest/gtest.h>

#include <cmath>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/enumeration.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

constexpr int kBits = 12;
constexpr double kFinalEps = 3.0;

TEST(EnumerationVsSmc, ImportanceMarginalsAgreeWithinMonteCarloError) {
  BinarySpaceOptions bits;
  bits.dimension = kBits;
  bits.prior_one = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2, 0.5, 0.6, 0.5, 0.35};
  bits.tied = {{9, 10}};  // a tie too, so both go through Expand
  const ParameterSpace space{BinarySpace(bits)};
  testing::IdentitySimulator sim{kBits};
  testing::WeightedL1Distance dist{{1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 1, 0},
                                   {4, 2, 2, 2, 1.5, 1.5, 1, 1, 1, 0.5, 0.5, 0},
                                   1,
                                   2,
                                   1.0};
  const SmcProblem problem{&space, &sim, &dist};

  EnumerationOptions exact_options;
  exact_options.thresholds = {kFinalEps};
  exact_options.threads = 2;
  const auto exact = Enumerate(problem, exact_options);
  ASSERT_EQ(exact.configurations, 1 << (kBits - 1));
  ASSERT_GT(exact.accepted, 10);

  SmcOptions o;
  o.num_waves = 5;
  o.accepted_per_wave = 3000;
  o.estimator = Estimator::kImportance;
  o.seed = 7;
  o.threads = 2;
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = {12, 8, 6, 4.5, kFinalEps};
  o.thresholds = {s};
  o.tempering.kind = TemperingKind::kLinear;
  o.tempering.phi0 = 0.5;
  const RunHistory h = RunCombinatorialSmc(problem, o);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  const WaveRecord& last = h.waves.back();
  ASSERT_EQ(last.thresholds[0], kFinalEps);
  for (int k = 0; k < kBits; ++k) {
    const double p = exact.marginals[k];
    // A floor for exact 0/1 marginals, whose binomial error is 0.
    const double bound = 5.0 * std::sqrt(p * (1.0 - p) / last.ess) + 2e-3;
    EXPECT_NEAR(last.marginals_importance[k], p, bound) << "bit " << k << ", ESS " << last.ess;
  }
}

}  // namespace
}  // namespace combabc
