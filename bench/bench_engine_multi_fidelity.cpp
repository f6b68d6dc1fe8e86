// Multi-fidelity ABC-SMC against the expensive model alone (docs/benchmarks.md): a 12-bit toy whose
// expensive simulator burns a fixed 200 us of CPU and whose cheap one burns 10 us (cost ratio 20)
// and reports one bit inverted. Counters: expensive and cheap simulator calls, the final wave's
// ESS, and ESS per unit cost (cost in expensive-simulation units: expensive + cheap / 20).
#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "combabc/samplers/combinatorial_smc.hpp"

namespace {

using namespace combabc;

constexpr int kBits = 12;

// Output = bits (bit `flip` inverted, if >= 0) after spinning for `seconds`.
class SpinSimulator : public Simulator {
 public:
  SpinSimulator(double seconds, int flip) : seconds_(seconds), flip_(flip) {}
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    calls_.fetch_add(1, std::memory_order_relaxed);
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds_);
    while (std::chrono::steady_clock::now() < until) {
    }
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
    if (flip_ >= 0) out[flip_] = 1.0 - out[flip_];
  }
  std::int64_t calls() const { return calls_.load(); }

 private:
  double seconds_;
  int flip_;
  mutable std::atomic<std::int64_t> calls_{0};
};

// Weighted L1 distance to the observed bits 1010...; bit 11 (the one the cheap model gets wrong)
// weighs least.
class ToyDistance : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"l1", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double s = 0.0;
    for (int k = 0; k < kBits; ++k) {
      s += (k == kBits - 1 ? 0.25 : 1.0) * std::abs(y[k] - static_cast<double>(k % 2 == 0));
    }
    out[0] = s;
  }
};

// range(0): 0 the expensive model alone; 1 multi-fidelity with the cost ratio given (20); 2
// multi-fidelity with the cost ratio measured. range(1): 0 thresholds 4, 3, 2, 1, where the cheap
// model's error of 0.5 on bit 11 decides many candidates; 1 thresholds 4.25, 3.25, 2.25, 1.25,
// where it decides none (a cheap model that ranks like the expensive one).
void BM_MultiFidelity(benchmark::State& state) {
  const ParameterSpace space(BinarySpace::Independent(kBits));
  const SpinSimulator expensive(200e-6, -1);
  const SpinSimulator cheap(10e-6, kBits - 1);
  const ToyDistance distance;
  SmcOptions o;
  o.num_waves = 4;
  o.accepted_per_wave = 1000;
  o.threads = 1;
  o.keep_outputs = false;
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = state.range(1) == 0 ? std::vector<double>{4.0, 3.0, 2.0, 1.0}
                                 : std::vector<double>{4.5, 3.5, 2.5, 1.5};
  o.thresholds = {s};
  o.multi_fidelity.cost_ratio = state.range(0) == 1 ? 20.0 : 0.0;
  SmcProblem problem{&space, &expensive, &distance};
  if (state.range(0) > 0) problem.low_fidelity = &cheap;
  double ess = 0.0;
  for (auto _ : state) {
    const auto history = RunCombinatorialSmc(problem, o);
    ess = history.waves.back().ess;
    if (const auto& f = history.waves.back().multi_fidelity) {
      state.counters["last_eta_1"] = f->continue_if_accepted;
      state.counters["last_eta_2"] = f->continue_if_rejected;
    }
  }
  const auto runs = static_cast<double>(state.iterations());
  const double expensive_calls = static_cast<double>(expensive.calls()) / runs;
  const double cheap_calls = static_cast<double>(cheap.calls()) / runs;
  state.counters["expensive_calls"] = expensive_calls;
  state.counters["cheap_calls"] = cheap_calls;
  state.counters["ess"] = ess;
  state.counters["ess_per_cost"] = ess / (expensive_calls + cheap_calls / 20.0);
}
BENCHMARK(BM_MultiFidelity)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
