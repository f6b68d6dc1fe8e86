// Time per clamp configuration of the default sensor: the condensed fast path against the full
// sparse solve of the same mesh, the precompute, and a threaded batch (docs/benchmarks.md).
#include <cstdint>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "combabc/plate/sensor_model.hpp"

namespace {

using combabc::plate::SensorModel;
using combabc::plate::SensorOptions;

std::vector<std::vector<std::uint8_t>> Configurations(int count, int clamps) {
  std::mt19937_64 rng(2024);
  std::vector<std::vector<std::uint8_t>> all(count, std::vector<std::uint8_t>(clamps));
  for (auto& c : all) {
    for (auto& v : c) v = static_cast<std::uint8_t>(rng() & 1);
  }
  return all;
}

const SensorModel& DefaultModel() {
  static const SensorModel model{SensorOptions{}};
  return model;
}

void BM_SensorPrecompute(benchmark::State& state) {
  for (auto _ : state) {
    SensorModel model{SensorOptions{}};
    benchmark::DoNotOptimize(&model);
  }
  state.counters["precomputed_MiB"] =
      static_cast<double>(DefaultModel().PrecomputedBytes()) / (1024.0 * 1024.0);
}
BENCHMARK(BM_SensorPrecompute)->Unit(benchmark::kMillisecond);

void BM_SensorProfileFast(benchmark::State& state) {
  const SensorModel& model = DefaultModel();
  const auto configs = Configurations(256, model.num_clamps());
  std::vector<double> out(model.num_outputs());
  std::size_t i = 0;
  for (auto _ : state) {
    model.Profile(configs[i++ % configs.size()], out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_SensorProfileFast)->Unit(benchmark::kMicrosecond);

// The same fast path with the pivoting-LU block solve forced (SensorOptions::always_pivot).
void BM_SensorProfileFastPivotingLu(benchmark::State& state) {
  SensorOptions options;
  options.always_pivot = true;
  static const SensorModel model{options};
  const auto configs = Configurations(256, model.num_clamps());
  std::vector<double> out(model.num_outputs());
  std::size_t i = 0;
  for (auto _ : state) {
    model.Profile(configs[i++ % configs.size()], out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_SensorProfileFastPivotingLu)->Unit(benchmark::kMicrosecond);

void BM_SensorProfileFullSolve(benchmark::State& state) {
  const SensorModel& model = DefaultModel();
  const auto configs = Configurations(16, model.num_clamps());
  std::vector<double> out(model.num_outputs());
  std::size_t i = 0;
  for (auto _ : state) {
    model.ProfileFullSolve(configs[i++ % configs.size()], out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_SensorProfileFullSolve)->Unit(benchmark::kMillisecond);

// Threaded batch; items/s is configurations per second.
void BM_SensorProfileBatch(benchmark::State& state) {
  const SensorModel& model = DefaultModel();
  const int n = 512;
  const auto configs = Configurations(n, model.num_clamps());
  std::vector<std::uint8_t> flat;
  for (const auto& c : configs) flat.insert(flat.end(), c.begin(), c.end());
  std::vector<double> out(static_cast<std::size_t>(n) * model.num_outputs());
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    model.ProfileBatch(flat, n, out, threads);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_SensorProfileBatch)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
