// Continuous and mixed parameters against posteriors we can compute: a Gaussian model whose ABC
// posterior is a one-dimensional integral (quadrature), a mixed bits x real toy (enumeration over
// the bits x quadrature over the real), and simulation-based calibration (Talts et al. 2018) over
// 200 replicates. Fixed seeds; bounds of 5 Monte-Carlo standard errors from the ESS.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "linear_gaussian.hpp"

namespace combabc {
namespace {

using testing::AbsoluteDistance;
using testing::ExactPosterior;
using testing::LinearGaussianSimulator;

SmcOptions ListOptions(std::vector<double> eps,
                       ContinuousKernelKind kernel,
                       int n,
                       std::uint64_t seed) {
  SmcOptions o;
  o.num_waves = static_cast<int>(eps.size());
  o.accepted_per_wave = n;
  o.seed = seed;
  o.threads = 2;
  o.proposal.continuous = kernel;
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = std::move(eps);
  o.thresholds = {s};
  return o;
}

struct Moments {
  double mean = 0, var = 0;
};
Moments RealMoments(const WaveRecord& wave) {
  Moments m;
  for (const auto& p : wave.particles) m.mean += p.weight * p.theta.reals[0];
  for (const auto& p : wave.particles) {
    m.var += p.weight * (p.theta.reals[0] - m.mean) * (p.theta.reals[0] - m.mean);
  }
  return m;
}

class ContinuousExactness : public ::testing::TestWithParam<ContinuousKernelKind> {};

// theta ~ N(1, 2^2), y* = theta + N(0, 0.5^2), y = 3, eps = 0.2: a continuous-only space (no
// bits), under either binary kernel, which then has nothing to fit.
TEST_P(ContinuousExactness, GaussianModelMatchesItsAbcPosterior) {
  ContinuousPrior prior;
  prior.kind = PriorKind::kNormal;
  prior.mean = 1.0;
  prior.sd = 2.0;
  const ParameterSpace space(BinarySpace::Independent(0), {{"theta", prior}});
  const LinearGaussianSimulator sim({}, 0.5);
  const AbsoluteDistance dist(3.0);
  const auto exact = ExactPosterior({}, {}, prior, 0.5, 3.0, 0.2, -15.0, 17.0);
  for (const auto binary : {BinaryKernelKind::kIndependent, BinaryKernelKind::kLogistic}) {
    auto o = ListOptions({2.0, 1.0, 0.5, 0.2}, GetParam(), 3000, 31);
    o.proposal.binary = binary;
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
    const auto& last = h.waves.back();
    const auto got = RealMoments(last);
    std::printf(
        "%s x %s: mean %.4f (exact %.4f), var %.4f (exact %.4f), ESS %.0f, %lld "
        "simulations\n",
        ToString(binary),
        ToString(GetParam()),
        got.mean,
        exact.mean,
        got.var,
        exact.var,
        last.ess,
        static_cast<long long>(h.summary.simulations));
    ASSERT_GT(last.ess, 500.0);
    EXPECT_TRUE(last.marginals_importance.empty());
    for (const auto& p : last.particles) EXPECT_TRUE(p.theta.bits.empty());
    // Standard errors of a mean and of a variance (Gaussian kurtosis) from ESS samples.
    EXPECT_NEAR(got.mean, exact.mean, 5.0 * std::sqrt(exact.var / last.ess));
    EXPECT_NEAR(got.var, exact.var, 5.0 * exact.var * std::sqrt(2.0 / last.ess));
    // The summary statistics the history stores agree with the particles.
    EXPECT_NEAR(last.reals_mean[0], got.mean, 1e-12);
    EXPECT_NEAR(last.reals_sd[0], std::sqrt(got.var), 1e-9);
  }
}

// Bits b1..b3 (weights 1, -0.5, 2) plus theta ~ U(-2, 2); y = 1.7, sigma = 0.3, eps = 0.25.
TEST_P(ContinuousExactness, MixedBitsAndRealMatchEnumerationTimesQuadrature) {
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -2.0;
  prior.high = 2.0;
  const std::vector<double> w = {1.0, -0.5, 2.0};
  const std::vector<double> bit_prior = {0.5, 0.3, 0.6};
  BinarySpaceOptions so;
  so.dimension = 3;
  so.prior_one = bit_prior;
  const ParameterSpace space(BinarySpace(so), {{"theta", prior}});
  const LinearGaussianSimulator sim(w, 0.3);
  const AbsoluteDistance dist(1.7);
  for (const auto binary : {BinaryKernelKind::kIndependent, BinaryKernelKind::kLogistic}) {
    auto o = ListOptions({2.0, 1.0, 0.5, 0.25}, GetParam(), 3000, 32);
    o.proposal.binary = binary;
    o.tempering.kind = TemperingKind::kLinear;
    o.tempering.phi0 = 0.3;
    o.tempering.form = TemperingForm::kMixture;
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
    const auto exact = ExactPosterior(w, bit_prior, prior, 0.3, 1.7, 0.25, -2.0, 2.0);
    const auto& last = h.waves.back();
    const auto got = RealMoments(last);
    std::printf("%s x %s: theta mean %.4f (exact %.4f), var %.4f (exact %.4f), ESS %.0f\n",
                ToString(binary),
                ToString(GetParam()),
                got.mean,
                exact.mean,
                got.var,
                exact.var,
                last.ess);
    ASSERT_GT(last.ess, 300.0);
    for (int k = 0; k < 3; ++k) {
      const double p = exact.bit_mean[k];
      EXPECT_NEAR(last.marginals_importance[k], p, 5.0 * std::sqrt(p * (1 - p) / last.ess) + 3e-3)
          << "bit " << k;
    }
    // A uniform prior's posterior is far from Gaussian: bound the variance's standard error by
    // the fourth moment of the support's half-width, 2.
    EXPECT_NEAR(got.mean, exact.mean, 5.0 * std::sqrt(exact.var / last.ess));
    EXPECT_NEAR(got.var, exact.var, 5.0 * 4.0 / std::sqrt(last.ess));
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels,
                         ContinuousExactness,
                         ::testing::Values(ContinuousKernelKind::kNormal,
                                           ContinuousKernelKind::kOlcm),
                         [](const auto& param_info) {
                           return std::string(ToString(param_info.param));
                         });

// Simulation-based calibration (Talts, Betancourt, Simpson, Vehtari & Gelman 2018): draw
// theta* from the prior, data from the model, and rank theta* among L draws from the computed
// posterior; for a correct sampler the ranks are uniform on {0..L}. ABC at a fixed eps is the
// exact posterior of the model y = y* + u, u uniform on [-eps, eps] ("noisy ABC", Fearnhead &
// Prangle 2012), so the data get that u too. 200 replicates, L = 9: 10 bins of 20 expected.
TEST(SimulationBasedCalibration, RanksAreUniform) {
  ContinuousPrior prior;
  prior.kind = PriorKind::kNormal;
  prior.mean = 0.0;
  prior.sd = 1.0;
  const ParameterSpace space(BinarySpace::Independent(0), {{"theta", prior}});
  const LinearGaussianSimulator sim({}, 0.5);
  constexpr int kReplicates = 200, kDraws = 9;
  constexpr double kEps = 0.2;
  std::vector<int> bins(kDraws + 1, 0);
  for (int r = 0; r < kReplicates; ++r) {
    RandomStream rng(2026, 1, static_cast<std::uint64_t>(r));
    const double truth = prior.Sample(rng);
    const double y = truth + 0.5 * rng.Normal() + kEps * (2.0 * rng.Uniform() - 1.0);
    const AbsoluteDistance dist(y);
    const auto h = RunCombinatorialSmc({&space, &sim, &dist},
                                       ListOptions({1.5, 0.6, kEps},
                                                   ContinuousKernelKind::kNormal,
                                                   300,
                                                   100 + static_cast<std::uint64_t>(r)));
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
    // L draws from the weighted particles (multinomial resampling from the replicate's stream).
    const auto& particles = h.waves.back().particles;
    std::vector<double> cumulative;
    cumulative.reserve(particles.size());
    double sum = 0;
    for (const auto& p : particles) cumulative.push_back(sum += p.weight);
    int rank = 0;
    for (int l = 0; l < kDraws; ++l) {
      const double u = rng.Uniform() * sum;
      const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), u);
      const auto i = std::min<std::size_t>(static_cast<std::size_t>(it - cumulative.begin()),
                                           particles.size() - 1);
      rank += particles[i].theta.reals[0] < truth;
    }
    ++bins[static_cast<std::size_t>(rank)];
  }
  const double expected = static_cast<double>(kReplicates) / (kDraws + 1);
  double chi2 = 0;
  for (int b : bins) chi2 += (b - expected) * (b - expected) / expected;
  std::printf("SBC rank counts:");
  for (int b : bins) std::printf(" %d", b);
  std::printf("; chi-square %.2f on %d degrees of freedom\n", chi2, kDraws);
  // 9 degrees of freedom: P(chi2 > 27.88) = 0.001. A sampler that over- or under-disperses its
  // posterior by a factor 1.5 piles ranks into the middle or the ends and fails this by far.
  EXPECT_LT(chi2, 27.88);
}

}  // namespace
}  // namespace combabc
