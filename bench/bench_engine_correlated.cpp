// Simulations needed to reach the final threshold, independent (Eq. 2) vs logistic kernel, at
// equal N, with the accuracy of each against the exact posterior (enumeration): on the d = 16
// problem whose posterior is a configuration and its complement, and on an independent one.
// The counters are the figures; the time is the engine's (the simulator is trivial).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "samplers/correlated_models.hpp"
#include "samplers/toy_models.hpp"

namespace combabc {
namespace {

const std::vector<std::uint8_t> kPattern = {1, 0, 0, 1, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 0};

void RunCase(benchmark::State& state,
             const Distance& distance,
             const std::vector<double>& prior,
             const std::vector<double>& thresholds) {
  const int d = static_cast<int>(prior.size());
  BinarySpaceOptions so;
  so.dimension = d;
  so.prior_one = prior;
  const ParameterSpace space{BinarySpace(so)};
  const testing::IdentitySimulator sim(d);
  SmcOptions o;
  o.num_waves = static_cast<int>(thresholds.size());
  o.accepted_per_wave = 500;
  o.threads = 1;
  o.keep_outputs = false;
  o.proposal.binary =
      state.range(0) == 0 ? BinaryKernelKind::kIndependent : BinaryKernelKind::kLogistic;
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = thresholds;
  o.thresholds = {s};
  o.tempering.kind = TemperingKind::kLinear;
  o.tempering.phi0 = 0.3;
  o.tempering.form = TemperingForm::kMixture;
  const auto exact = testing::ExactMoments(distance, prior, thresholds.back());
  double simulations = 0, last_wave = 0, mean_error = 0, corr_error = 0, ess = 0;
  for (auto _ : state) {
    const auto h = RunCombinatorialSmc({&space, &sim, &distance}, o);
    if (h.summary.termination != Termination::kTargetReached) state.SkipWithError("not reached");
    simulations = static_cast<double>(h.summary.simulations);
    last_wave = static_cast<double>(h.waves.back().candidates);
    ess = h.waves.back().ess;
    const auto got = testing::WaveMoments(h.waves.back());
    mean_error = corr_error = 0;
    for (int a = 0; a < d; ++a) {
      mean_error = std::max(mean_error, std::abs(got.mean[a] - exact.mean[a]));
      for (int b = a + 1; b < d; ++b) {
        corr_error = std::max(corr_error, std::abs(got.corr[a][b] - exact.corr[a][b]));
      }
    }
  }
  state.SetLabel(ToString(o.proposal.binary));
  state.counters["simulations"] = simulations;
  state.counters["last_wave_simulations"] = last_wave;
  state.counters["ess"] = ess;
  state.counters["max_marginal_error"] = mean_error;
  state.counters["max_correlation_error"] = corr_error;
}

void BM_ComplementD16(benchmark::State& state) {
  const testing::ComplementDistance distance(kPattern);
  RunCase(state, distance, std::vector<double>(16, 0.5), {5, 3, 2, 1});
}
BENCHMARK(BM_ComplementD16)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_IndependentD12(benchmark::State& state) {
  const testing::IndependentDistance distance({1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0, 0},
                                              {4, 2, 2, 2, 1.5, 1.5, 1, 1, 1, 0.5, 0.5, 0});
  RunCase(state,
          distance,
          {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2, 0.5, 0.6, 0.5, 0.35},
          {12, 8, 6, 4.5, 3});
}
BENCHMARK(BM_IndependentD12)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace combabc
