// Exactness of both binary kernels against enumeration, on problems that couple bits (a
// configuration and its complement; a chain) and on an independent one: the last wave's
// importance-weighted marginals and pair correlations must match the exact ABC posterior within
// Monte-Carlo bounds. Fixed seeds, so each check is deterministic; the bounds are 5 standard
// errors from the ESS, so a correct sampler passes them with any seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "correlated_models.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

struct Problem {
  std::string name;
  std::vector<double> prior;
  const Distance* distance;
  std::vector<double> thresholds;  // list schedule; the last is the final eps
};

double MarginalBound(double p, double ess) { return 5.0 * std::sqrt(p * (1.0 - p) / ess) + 3e-3; }
// The correlation estimator's standard error is about (1 - rho^2) / sqrt(ESS).
double CorrelationBound(double rho, double ess) {
  return 5.0 * (1.0 - rho * rho) / std::sqrt(ess) + 0.02;
}

void CheckKernel(const Problem& problem, BinaryKernelKind kernel, std::uint64_t seed) {
  const int d = static_cast<int>(problem.prior.size());
  BinarySpaceOptions so;
  so.dimension = d;
  so.prior_one = problem.prior;
  const ParameterSpace space{BinarySpace(so)};
  const testing::IdentitySimulator sim(d);
  SmcOptions o;
  o.num_waves = static_cast<int>(problem.thresholds.size());
  o.accepted_per_wave = 2000;
  o.seed = seed;
  o.threads = 2;
  o.proposal.binary = kernel;
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = problem.thresholds;
  o.thresholds = {s};
  o.tempering.kind = TemperingKind::kLinear;
  o.tempering.phi0 = 0.3;
  o.tempering.form = TemperingForm::kMixture;
  const auto history = RunCombinatorialSmc({&space, &sim, problem.distance}, o);
  ASSERT_EQ(history.summary.termination, Termination::kTargetReached) << problem.name;
  const auto& last = history.waves.back();
  const auto exact =
      testing::ExactMoments(*problem.distance, problem.prior, problem.thresholds.back());
  const auto got = testing::WaveMoments(last);
  std::printf("%s, %s kernel: %lld simulations, last wave ESS %.0f\n",
              problem.name.c_str(),
              ToString(kernel),
              static_cast<long long>(history.summary.simulations),
              last.ess);
  ASSERT_GT(last.ess, 200.0) << "too few effective samples for a meaningful check";
  for (int a = 0; a < d; ++a) {
    EXPECT_NEAR(got.mean[a], exact.mean[a], MarginalBound(exact.mean[a], last.ess))
        << problem.name << ", " << ToString(kernel) << ", bit " << a;
    for (int b = a + 1; b < d; ++b) {
      EXPECT_NEAR(got.corr[a][b], exact.corr[a][b], CorrelationBound(exact.corr[a][b], last.ess))
          << problem.name << ", " << ToString(kernel) << ", bits " << a << "," << b;
    }
  }
}

const std::vector<std::uint8_t> kPattern = {1, 0, 0, 1, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 0};

class KernelExactness : public ::testing::TestWithParam<BinaryKernelKind> {};

TEST_P(KernelExactness, ConfigurationAndItsComplement) {
  const testing::ComplementDistance distance(kPattern);
  CheckKernel(
      {"complement d=16", std::vector<double>(16, 0.5), &distance, {5, 3, 2, 1}}, GetParam(), 21);
}

TEST_P(KernelExactness, ChainCoupledBits) {
  const testing::ChainDistance distance;
  CheckKernel({"chain d=12",
               {0.5, 0.4, 0.6, 0.5, 0.5, 0.3, 0.5, 0.7, 0.5, 0.5, 0.45, 0.5},
               &distance,
               {4, 3, 2, 1.5}},
              GetParam(),
              22);
}

TEST_P(KernelExactness, IndependentBits) {
  const testing::IndependentDistance distance({1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0, 0},
                                              {4, 2, 2, 2, 1.5, 1.5, 1, 1, 1, 0.5, 0.5, 0});
  CheckKernel({"independent d=12",
               {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2, 0.5, 0.6, 0.5, 0.35},
               &distance,
               {12, 8, 6, 4.5, 3}},
              GetParam(),
              23);
}

INSTANTIATE_TEST_SUITE_P(Kernels,
                         KernelExactness,
                         ::testing::Values(BinaryKernelKind::kIndependent,
                                           BinaryKernelKind::kLogistic),
                         [](const auto& param_info) {
                           return std::string(ToString(param_info.param));
                         });

}  // namespace
}  // namespace combabc
