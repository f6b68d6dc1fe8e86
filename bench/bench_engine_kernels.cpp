// Binary proposal kernels per candidate (issue 9: sample + log density <= 2 us per candidate at
// d = 36) and the cost of fitting them (N = 500, d = 36: milliseconds); the joint kernels' sample +
// exact mixture density per candidate (issue 23). Linked against the engine only
// (bench/CMakeLists.txt); docs/benchmarks.md records the numbers.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>
#include <vector>

#include "combabc/proposals/logistic_kernel.hpp"
#include "combabc/proposals/proposal_options.hpp"

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

// A mixed population of N = 1000 particles, f = 8 free bits spread over `patterns` distinct
// patterns, `reals` reals around a centre per pattern.
Population MixedPopulation(std::size_t patterns, std::size_t reals) {
  constexpr std::size_t n = 1000, f = 8;
  Population p;
  p.size = n;
  p.num_free_bits = f;
  p.num_reals = reals;
  RandomStream rng(2025, 0, 0);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t g = j % patterns;
    for (std::size_t i = 0; i < f; ++i) {
      p.free_bits.push_back(static_cast<std::uint8_t>((g >> i) & 1U));
    }
    for (std::size_t k = 0; k < reals; ++k) {
      p.reals.push_back(static_cast<double>(g) + 0.1 * rng.Normal());
    }
    p.weights.push_back(1.0 / n);
  }
  p.within_next.assign(n, 1);
  return p;
}

// Per candidate: derive its stream, sample, and the exact log density. Args: kind (0 independent
// x normal, 1 ancestor), distinct patterns G, reals r.
void BM_JointSampleAndLogDensity(benchmark::State& state) {
  const auto patterns = static_cast<std::size_t>(state.range(1));
  const auto r = static_cast<std::size_t>(state.range(2));
  std::vector<ContinuousParameter> reals;
  for (std::size_t k = 0; k < r; ++k) {
    reals.push_back(
        {"r" + std::to_string(k), {.kind = PriorKind::kNormal, .mean = 0.0, .sd = 100.0}});
  }
  const ParameterSpace space(BinarySpace::Independent(8), reals);
  ProposalOptions o;
  o.binary = state.range(0) == 1 ? BinaryKernelKind::kAncestor : BinaryKernelKind::kIndependent;
  const auto q = MakeJointKernel(o, space)->Fit(MixedPopulation(patterns, r), space, {});
  std::vector<std::uint8_t> bits(8);
  std::vector<double> x(r);
  std::uint64_t index = 0;
  double sum = 0.0;
  for (auto _ : state) {
    RandomStream rng(7, 3, index++);
    q->Sample(rng, bits, x);
    sum += q->LogDensity(bits, x);
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_JointSampleAndLogDensity)
    ->ArgsProduct({{0, 1}, {1, 16, 256}, {1, 3}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
