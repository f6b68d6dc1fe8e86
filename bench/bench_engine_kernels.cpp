// Binary proposal kernels per candidate (issue 9: sample + log density <= 2 us per candidate at
// d = 36) and the cost of fitting them (N = 500, d = 36: milliseconds). Linked against the engine
// only (bench/CMakeLists.txt); docs/benchmarks.md records the numbers.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "combabc/proposals/logistic_kernel.hpp"

namespace {

using namespace combabc;

// A population with strong, long-range couplings: x_{i+1} = x_i with probability 0.9, so bit i
// is correlated with its predecessors at lags up to ~11 (0.8^lag > min_correlation) and most bits
// regress on a dozen predecessors: about the heaviest a fitted proposal gets at this size.
Population ChainPopulation(std::size_t d, std::size_t n) {
  Population p;
  p.size = n;
  p.num_free_bits = d;
  RandomStream rng(2024, 0, 0);
  for (std::size_t r = 0; r < n; ++r) {
    std::uint8_t x = rng.Uniform() < 0.5;
    for (std::size_t i = 0; i < d; ++i) {
      if (i > 0 && rng.Uniform() >= 0.9) x = static_cast<std::uint8_t>(1 - x);
      p.free_bits.push_back(x);
    }
    p.weights.push_back(0.5 + rng.Uniform());
  }
  double total = 0.0;
  for (const double w : p.weights) total += w;
  for (double& w : p.weights) w /= total;
  p.within_next.assign(n, 1);
  return p;
}

// Arg 0: phi = 0; 1: phi = 0.3 geometric; 2: phi = 0.3 mixture; 3: phi = 1 (the prior itself,
// the floor set by one Uniform and one table lookup per bit).
Tempering TemperingOf(std::int64_t arg) {
  switch (arg) {
    case 1:
      return {0.3, TemperingForm::kGeometric};
    case 2:
      return {0.3, TemperingForm::kMixture};
    case 3:
      return {1.0, TemperingForm::kGeometric};
    default:
      return {0.0, TemperingForm::kGeometric};
  }
}

// What the sampler does per candidate: derive the candidate's stream, sample, weigh.
void BM_LogisticSampleAndLogDensity(benchmark::State& state) {
  constexpr std::size_t d = 36;
  const auto q = MakeLogisticKernel({})->Fit(
      ChainPopulation(d, 500), std::vector<double>(d, 0.5), TemperingOf(state.range(0)));
  std::vector<std::uint8_t> bits(d);
  std::uint64_t index = 0;
  double sum = 0.0;
  for (auto _ : state) {
    RandomStream rng(7, 3, index++);
    q->Sample(rng, bits);
    sum += q->LogDensity(bits);
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LogisticSampleAndLogDensity)->DenseRange(0, 3);

void BM_LogisticFit(benchmark::State& state) {
  const auto d = static_cast<std::size_t>(state.range(0));
  const auto population = ChainPopulation(d, 500);
  const auto kernel = MakeLogisticKernel({});
  const std::vector<double> prior(d, 0.5);
  for (auto _ : state) {
    auto q = kernel->Fit(population, prior, {});
    benchmark::DoNotOptimize(q.get());
  }
}
BENCHMARK(BM_LogisticFit)->Arg(36)->Unit(benchmark::kMillisecond);

void BM_LogisticMarginals(benchmark::State& state) {
  constexpr std::size_t d = 36;
  const auto q =
      MakeLogisticKernel({})->Fit(ChainPopulation(d, 500), std::vector<double>(d, 0.5), {});
  for (auto _ : state) benchmark::DoNotOptimize(q->Marginals());
}
BENCHMARK(BM_LogisticMarginals)->Unit(benchmark::kMillisecond);

}  // namespace
