// Engine overhead and thread scaling (issue: <= 1 us per candidate with a trivial simulator at
// d = 36, 500 accepted x 5 waves; >= 90 % parallel efficiency on 2 cores with a 50 us simulator).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>

#include "combabc/samplers/combinatorial_smc.hpp"

namespace {

using namespace combabc;

// Output = bits; the cheapest possible simulator, so what is timed is the engine.
class TrivialSimulator : public Simulator {
 public:
  explicit TrivialSimulator(int d) : d_(d) {}
  int output_size() const override { return d_; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    for (int k = 0; k < d_; ++k) out[k] = theta.bits[k];
  }

 private:
  int d_;
};

// Spins for a fixed wall time, like a simulator with a fixed cost.
class SpinSimulator : public TrivialSimulator {
 public:
  SpinSimulator(int d, double seconds) : TrivialSimulator(d), seconds_(seconds) {}
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds_);
    while (std::chrono::steady_clock::now() < until) {
    }
    TrivialSimulator::Simulate(theta, rng, out);
  }

 private:
  double seconds_;
};

class HammingDistance : public Distance {
 public:
  explicit HammingDistance(int d) : d_(d) {}
  std::vector<DistanceComponent> components() const override {
    return {{"hamming", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double s = 0.0;
    for (int k = 0; k < d_; ++k) s += std::abs(y[k] - static_cast<double>(k % 3 == 0));
    out[0] = s;
  }

 private:
  int d_;
};

SmcOptions PaperLikeOptions(int threads) {
  SmcOptions o;
  o.num_waves = 5;
  o.accepted_per_wave = 500;
  o.threads = threads;
  o.thresholds.resize(1);  // adaptive median thresholds from eps_0 = inf
  o.tempering.kind = TemperingKind::kLinear;
  o.tempering.phi0 = 0.3;
  return o;
}

// range(0) = d, range(1) = the binary kernel (0 independent, 1 logistic).
void BM_EngineOverheadPerCandidate(benchmark::State& state) {
  const int d = static_cast<int>(state.range(0));
  const ParameterSpace space(BinarySpace::Independent(d));
  TrivialSimulator sim(d);
  HammingDistance dist(d);
  auto options = PaperLikeOptions(1);
  options.keep_outputs = false;
  options.proposal.binary =
      state.range(1) == 0 ? BinaryKernelKind::kIndependent : BinaryKernelKind::kLogistic;
  state.SetLabel(ToString(options.proposal.binary));
  std::int64_t candidates = 0;
  for (auto _ : state) {
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, options);
    candidates += h.summary.simulations + h.summary.simulations_discarded;
    benchmark::DoNotOptimize(h.waves.back().marginals_importance.data());
  }
  state.SetItemsProcessed(candidates);
  state.counters["ns_per_candidate"] = benchmark::Counter(
      static_cast<double>(candidates), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["candidates_per_run"] =
      static_cast<double>(candidates) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_EngineOverheadPerCandidate)
    ->Args({36, 0})
    ->Args({36, 1})
    ->Args({1024, 0})
    ->Unit(benchmark::kMillisecond);

void BM_ThreadScaling50us(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const ParameterSpace space(BinarySpace::Independent(36));
  SpinSimulator sim(36, 50e-6);
  HammingDistance dist(36);
  auto options = PaperLikeOptions(threads);
  options.num_waves = 2;
  options.accepted_per_wave = 500;
  std::int64_t candidates = 0;
  for (auto _ : state) {
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, options);
    candidates += h.summary.simulations + h.summary.simulations_discarded;
  }
  state.SetItemsProcessed(candidates);
}
BENCHMARK(BM_ThreadScaling50us)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
