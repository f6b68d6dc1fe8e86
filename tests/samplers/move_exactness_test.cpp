// Resample-move waves (SamplerMethod::kResampleMove, docs/algorithm.md "Resample-move") against
// exact posteriors: the coupled-bit problems of kernel_exactness_test.cpp (enumerated), the
// noise-aware linear problem of noise_aware_test.cpp (enumerated likelihood posterior), and the
// mixed minor-modes problem (enumeration x quadrature). The last wave's marginals must be within
// 5 Monte-Carlo standard errors of the exact ones, the errors being the run's own (clustered by
// ancestor: moved particles of one ancestor are correlated). Fixed seeds: deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "correlated_models.hpp"
#include "minor_modes.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

SmcOptions MoveOptions(std::vector<double> thresholds, int n, std::uint64_t seed) {
  SmcOptions o;
  o.method = SamplerMethod::kResampleMove;
  o.num_waves = 30;
  o.accepted_per_wave = n;
  o.seed = seed;
  o.threads = 2;
  ThresholdSchedule s;
  s.target = thresholds.back();
  o.thresholds = {s};
  return o;
}

// The last wave's bit marginals within 5 of its own standard errors (plus a small floor for an
// exact 0 or 1) of `exact`.
void PrintWaves(const RunHistory& h) {
  for (const auto& w : h.waves) {
    std::printf("  wave %d eps %.4g candidates %lld rate %.3f", w.wave + 1, w.thresholds.at(0),
                static_cast<long long>(w.candidates), w.acceptance_rate);
    if (w.moves) {
      std::printf(" step %.3f survivors %.1f rounds %d indep %lld/%lld", w.moves->step,
                  w.moves->survivor_ess, w.moves->rounds,
                  static_cast<long long>(w.moves->independent_accepted),
                  static_cast<long long>(w.moves->independent_proposed));
    }
    std::printf("\n");
  }
}

void ExpectMarginals(const RunHistory& h, const std::vector<double>& exact, const char* name) {
  const auto& last = h.waves.back();
  const WaveErrors errors = WaveMonteCarloErrors(last);
  ASSERT_TRUE(last.moves.has_value()) << name << ": the last wave was not a move wave";
  std::printf("%s: %zu waves, %lld simulations, last wave %d rounds, %.0f%% accepted\n",
              name,
              h.waves.size(),
              static_cast<long long>(h.summary.simulations),
              last.moves->rounds,
              100.0 * last.acceptance_rate);
  for (std::size_t k = 0; k < exact.size(); ++k) {
    const auto& m = errors.bits[k];
    std::printf("  bit %2zu exact %.4f got %.4f se %.4f\n", k, exact[k], m.value, m.se);
    EXPECT_NEAR(m.value, exact[k], 5.0 * m.se + 2e-3) << name << ", bit " << k;
  }
}

TEST(MoveExactness, ConfigurationAndItsComplement) {
  const std::vector<std::uint8_t> pattern = {1, 0, 0, 1, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 0};
  const testing::ComplementDistance distance(pattern);
  const std::vector<double> prior(16, 0.5);
  const ParameterSpace space{BinarySpace::Independent(16)};
  const testing::IdentitySimulator sim(16);
  const auto h = RunCombinatorialSmc({&space, &sim, &distance}, MoveOptions({1}, 1000, 21));
  PrintWaves(h);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  const auto exact = testing::ExactMoments(distance, prior, 1.0).mean;
  ExpectMarginals(h, exact, "complement d=16");
}

TEST(MoveExactness, ChainCoupledBits) {
  const testing::ChainDistance distance;
  const std::vector<double> prior = {0.5, 0.4, 0.6, 0.5, 0.5, 0.3, 0.5, 0.7, 0.5, 0.5, 0.45, 0.5};
  BinarySpaceOptions so;
  so.dimension = 12;
  so.prior_one = prior;
  const ParameterSpace space{BinarySpace(so)};
  const testing::IdentitySimulator sim(12);
  const auto h = RunCombinatorialSmc({&space, &sim, &distance}, MoveOptions({1.5}, 1000, 22));
  PrintWaves(h);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  const auto exact = testing::ExactMoments(distance, prior, 1.5).mean;
  ExpectMarginals(h, exact, "chain d=12");
}

}  // namespace
}  // namespace combabc
