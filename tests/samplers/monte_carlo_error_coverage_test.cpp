// The Monte-Carlo standard errors against the spread over seeds (docs/benchmarks.md, "Monte-Carlo
// error coverage"): on problems with an exact ABC posterior, a fixed set of seeds, and the mean of
// z^2 = ((estimate - exact) / SE)^2 over seeds and quantities, which is 1 for honest standard
// errors. The bounds (a spread between 0.63x and 1.5x the SE) hold for the delta-method SEs
// (samplers/monte_carlo_error.hpp) and fail for the ESS-based ones they replaced (sd / sqrt(ESS)
// for a mean, sd / sqrt(2 ESS) for an sd), which the mixture toy's heavy tails put 1.9-3.4x too
// low. Fixed seeds: the outcome is deterministic (histories do not depend on thread counts).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "linear_gaussian.hpp"
#include "mixture_model.hpp"

namespace combabc {
namespace {

constexpr int kSeeds = 20;

// Sums of z^2 and counts.
struct ZSquared {
  double sum = 0.0;
  int n = 0;
  void Add(double estimate, double exact, double se) {
    const double z = (estimate - exact) / se;
    sum += z * z;
    ++n;
  }
  double Mean() const { return sum / n; }
};

SmcOptions ListOptions(std::vector<double> eps, int n, std::uint64_t seed) {
  SmcOptions o;
  o.num_waves = static_cast<int>(eps.size());
  o.accepted_per_wave = n;
  o.seed = seed;
  o.threads = 2;
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = std::move(eps);
  o.thresholds = {s};
  return o;
}

// The mixture toy at eps = 0.05: its posterior mean and sd, 20 seeds of 1000 particles.
TEST(MonteCarloErrorCoverage, DeltaMethodErrorsMatchTheSpreadOnAHeavyTailedPosterior) {
  const ParameterSpace space(BinarySpace::Independent(0), {{"theta", testing::MixturePrior()}});
  const testing::MixtureSimulator sim;
  const testing::AbsoluteDistance dist(0.0);
  const std::vector<double> eps = {2.0, 0.5, 0.1, 0.05};
  const testing::MixtureMoments exact = testing::ExactMixtureMoments(eps.back());
  ZSquared delta, ess_based;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const RunHistory h =
        RunCombinatorialSmc({&space, &sim, &dist}, ListOptions(eps, 1000, 100 + seed));
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
    const WaveRecord& last = h.waves.back();
    const WaveErrors e = WaveMonteCarloErrors(last);
    const double sd = e.real_sds[0].value;
    delta.Add(e.real_means[0].value, exact.mean, e.real_means[0].se);
    delta.Add(sd, exact.sd, e.real_sds[0].se);
    ess_based.Add(e.real_means[0].value, exact.mean, sd / std::sqrt(last.ess));
    ess_based.Add(sd, exact.sd, sd / std::sqrt(2.0 * last.ess));
  }
  std::printf("mean z^2 over %d seeds: delta method %.2f, ESS-based %.2f\n",
              kSeeds,
              delta.Mean(),
              ess_based.Mean());
  // Honest: about 1 (1.42 with these seeds); a spread 1.5x the SE is a mean z^2 of 2.25. The
  // ESS-based errors give 8.3.
  EXPECT_GT(delta.Mean(), 0.4);
  EXPECT_LT(delta.Mean(), 2.25);
  EXPECT_GT(ess_based.Mean(), 2.25) << "the test no longer tells the old errors from honest ones";
}

// The mixed toy of continuous_test.cpp (3 bits x a uniform real), 20 seeds of 500 particles:
// every reported quantity, P(bit = 1), the configuration masses above 0.01, the real's mean and
// sd.
TEST(MonteCarloErrorCoverage, DeltaMethodErrorsMatchTheSpreadOnAMixedToy) {
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
  const testing::LinearGaussianSimulator sim(w, 0.3);
  const testing::AbsoluteDistance dist(1.7);
  const auto exact = testing::ExactPosterior(w, bit_prior, prior, 0.3, 1.7, 0.25, -2.0, 2.0);
  ZSquared bits, masses, reals;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const RunHistory h = RunCombinatorialSmc({&space, &sim, &dist},
                                             ListOptions({2.0, 1.0, 0.5, 0.25}, 500, 200 + seed));
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
    const WaveRecord& last = h.waves.back();
    const WaveErrors e = WaveMonteCarloErrors(last);
    for (std::size_t k = 0; k < 3; ++k) bits.Add(e.bits[k].value, exact.bit_mean[k], e.bits[k].se);
    std::vector<double> weights;
    for (const Particle& p : last.particles) weights.push_back(p.weight);
    for (std::size_t c = 0; c < exact.configuration_mass.size(); ++c) {
      if (exact.configuration_mass[c] < 0.01) continue;
      std::vector<double> in;
      for (const Particle& p : last.particles) {
        std::size_t code = 0;
        for (std::size_t k = 0; k < 3; ++k) code |= std::size_t{p.theta.bits[k]} << k;
        in.push_back(code == c ? 1.0 : 0.0);
      }
      const WeightedMoment m = WeightedMean(weights, in);
      masses.Add(m.value, exact.configuration_mass[c], m.se);
    }
    reals.Add(e.real_means[0].value, exact.mean, e.real_means[0].se);
    reals.Add(e.real_sds[0].value, std::sqrt(exact.var), e.real_sds[0].se);
  }
  std::printf("mean z^2 over %d seeds: bits %.2f, masses %.2f, mean and sd %.2f\n",
              kSeeds,
              bits.Mean(),
              masses.Mean(),
              reals.Mean());
  for (const ZSquared* z : {&bits, &masses, &reals}) {
    EXPECT_GT(z->Mean(), 0.4);
    EXPECT_LT(z->Mean(), 2.25);
  }
}

}  // namespace
}  // namespace combabc
