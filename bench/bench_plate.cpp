// Time per clamp configuration of the default sensor: the condensed fast path against the full
// sparse solve of the same mesh, the precompute, and a threaded batch (docs/benchmarks.md); and
// the same with continuous unknowns per call (SensorVariation, docs/model.md).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "combabc/core/thread_pool.hpp"
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

// The fast path over 256 random configurations in turn (more than the caches hold of the pieces
// they read, as in a calibration).
void ProfileLoop(benchmark::State& state, const SensorModel& model) {
  const auto configs = Configurations(256, model.num_clamps());
  std::vector<double> out(model.num_outputs());
  std::size_t i = 0;
  for (auto _ : state) {
    model.Profile(configs[i++ % configs.size()], out);
    benchmark::DoNotOptimize(out.data());
  }
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

// The precompute on a pool of state.range(0) threads (the CLI lends the executor's): wall time
// (UseRealTime), as CPU time is the calling thread's alone.
void BM_SensorPrecomputeThreads(benchmark::State& state) {
  combabc::ThreadPool pool(static_cast<int>(state.range(0)));
  combabc::plate::PrecomputeOptions precompute;
  precompute.pool = &pool;
  for (auto _ : state) {
    SensorModel model{SensorOptions{}, precompute};
    benchmark::DoNotOptimize(&model);
  }
}
BENCHMARK(BM_SensorPrecomputeThreads)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// A warm start: the default sensor read from the precompute cache (a folder of its own, filled
// before timing starts).
void BM_SensorFromCache(benchmark::State& state) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / "combabc-bench-precompute-cache";
  combabc::plate::PrecomputeOptions precompute;
  precompute.cache_directory = folder.string();
  { const SensorModel fill{SensorOptions{}, precompute}; }
  bool hit = true;
  for (auto _ : state) {
    SensorModel model{SensorOptions{}, precompute};
    hit = hit && model.precompute_from_cache();
    benchmark::DoNotOptimize(&model);
  }
  if (!hit) state.SkipWithError("the model was not read from the cache");
  std::error_code ec;
  std::filesystem::remove_all(folder, ec);
}
BENCHMARK(BM_SensorFromCache)->Unit(benchmark::kMillisecond);

void BM_SensorProfileFast(benchmark::State& state) {
  const SensorModel& model = DefaultModel();
  ProfileLoop(state, model);
}
BENCHMARK(BM_SensorProfileFast)->Unit(benchmark::kMicrosecond);

// Several load cases (SensorOptions::load_cases; docs/model.md, "Several load cases"): the first
// k of loads at 0.45, 0.70, 0.20 and 0.60 m, each with the default outputs. One factorization per
// configuration serves every case, so k cases should cost far less than k times one (target:
// 1 + 0.25 (k - 1) times k = 1; docs/benchmarks.md).
SensorOptions LoadCaseOptions(int k) {
  SensorOptions options;
  options.load_cases.clear();
  for (const double x : {0.45, 0.70, 0.20, 0.60}) {
    if (static_cast<int>(options.load_cases.size()) == k) break;
    combabc::plate::LoadCase c;
    c.load_x = x;
    options.load_cases.push_back(c);
  }
  return options;
}

void BM_SensorProfileLoadCases(benchmark::State& state) {
  const SensorModel model{LoadCaseOptions(static_cast<int>(state.range(0)))};
  ProfileLoop(state, model);
}
BENCHMARK(BM_SensorProfileLoadCases)->DenseRange(1, 4)->Unit(benchmark::kMicrosecond);

void BM_SensorPrecomputeLoadCases(benchmark::State& state) {
  const SensorOptions options = LoadCaseOptions(static_cast<int>(state.range(0)));
  std::size_t bytes = 0;
  for (auto _ : state) {
    SensorModel model{options};
    bytes = model.PrecomputedBytes();
    benchmark::DoNotOptimize(&model);
  }
  state.counters["precomputed_MiB"] = static_cast<double>(bytes) / (1024.0 * 1024.0);
}
BENCHMARK(BM_SensorPrecomputeLoadCases)->DenseRange(1, 4)->Unit(benchmark::kMillisecond);

// The same fast path on each instruction set (SensorOptions::vector_kernels: 1 the build's own,
// 2 AVX2, 3 AVX-512; the default takes the widest the CPU has, all with bit-identical results).
void BM_SensorProfileFastKernels(benchmark::State& state) {
  SensorOptions options;
  options.vector_kernels = static_cast<combabc::plate::VectorKernels>(state.range(0));
  if (combabc::ValidationError error; !options.IsValid(&error)) {
    state.SkipWithError("this CPU lacks the instruction set");
    return;
  }
  const SensorModel model{options};
  ProfileLoop(state, model);
}
BENCHMARK(BM_SensorProfileFastKernels)->DenseRange(1, 3)->Unit(benchmark::kMicrosecond);

// The same fast path with the pivoting-LU block solve forced (SensorOptions::always_pivot).
void BM_SensorProfileFastPivotingLu(benchmark::State& state) {
  SensorOptions options;
  options.always_pivot = true;
  static const SensorModel model{options};
  ProfileLoop(state, model);
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

// The same three per theory at that theory's default mesh (docs/model.md, "Plate theories"):
// Kirchhoff (BFS, 10 x 6 per section), first-order shear deformation (MITC9, 3 dofs per node)
// and the refined zigzag theory (RZT9, 5 dofs per node), both 10 x 3 quadratic elements; the
// plain benchmarks above are the default sensor, RZT.
SensorOptions TheoryOptions(combabc::plate::PlateTheory theory) {
  SensorOptions options;
  options.theory = theory;
  return options;
}

void SensorPrecompute(benchmark::State& state, combabc::plate::PlateTheory theory) {
  for (auto _ : state) {
    SensorModel model{TheoryOptions(theory)};
    benchmark::DoNotOptimize(&model);
  }
}

// Arg: mesh refinement factor in both directions (1 = the theory's default mesh).
void SensorProfileFast(benchmark::State& state, combabc::plate::PlateTheory theory) {
  SensorOptions options = TheoryOptions(theory);
  options.elements_per_section *= static_cast<int>(state.range(0));
  options.elements_across_width = options.ElementsAcrossWidth() * static_cast<int>(state.range(0));
  const SensorModel model{options};
  ProfileLoop(state, model);
}

void SensorProfileFullSolve(benchmark::State& state, combabc::plate::PlateTheory theory) {
  const SensorModel model{TheoryOptions(theory)};
  const auto configs = Configurations(16, model.num_clamps());
  std::vector<double> out(model.num_outputs());
  std::size_t i = 0;
  for (auto _ : state) {
    model.ProfileFullSolve(configs[i++ % configs.size()], out);
    benchmark::DoNotOptimize(out.data());
  }
}

void BM_SensorPrecomputeKirchhoff(benchmark::State& state) {
  SensorPrecompute(state, combabc::plate::PlateTheory::kKirchhoff);
}
BENCHMARK(BM_SensorPrecomputeKirchhoff)->Unit(benchmark::kMillisecond);
void BM_SensorProfileFastKirchhoff(benchmark::State& state) {
  SensorProfileFast(state, combabc::plate::PlateTheory::kKirchhoff);
}
BENCHMARK(BM_SensorProfileFastKirchhoff)->Arg(1)->Unit(benchmark::kMicrosecond);
void BM_SensorProfileFullSolveKirchhoff(benchmark::State& state) {
  SensorProfileFullSolve(state, combabc::plate::PlateTheory::kKirchhoff);
}
BENCHMARK(BM_SensorProfileFullSolveKirchhoff)->Unit(benchmark::kMillisecond);

void BM_SensorPrecomputeFsdt(benchmark::State& state) {
  SensorPrecompute(state, combabc::plate::PlateTheory::kFsdt);
}
BENCHMARK(BM_SensorPrecomputeFsdt)->Unit(benchmark::kMillisecond);
void BM_SensorProfileFastFsdt(benchmark::State& state) {
  SensorProfileFast(state, combabc::plate::PlateTheory::kFsdt);
}
BENCHMARK(BM_SensorProfileFastFsdt)->Arg(1)->Unit(benchmark::kMicrosecond);
void BM_SensorProfileFullSolveFsdt(benchmark::State& state) {
  SensorProfileFullSolve(state, combabc::plate::PlateTheory::kFsdt);
}
BENCHMARK(BM_SensorProfileFullSolveFsdt)->Unit(benchmark::kMillisecond);

void BM_SensorPrecomputeRzt(benchmark::State& state) {
  SensorPrecompute(state, combabc::plate::PlateTheory::kRzt);
}
BENCHMARK(BM_SensorPrecomputeRzt)->Unit(benchmark::kMillisecond);
void BM_SensorProfileFastRzt(benchmark::State& state) {
  SensorProfileFast(state, combabc::plate::PlateTheory::kRzt);
}
BENCHMARK(BM_SensorProfileFastRzt)->Arg(1)->Unit(benchmark::kMicrosecond);
// RZT on other meshes. Args: element order (1: bilinear RZT4, 2: quadratic RZT9), elements per
// section and across the width; 3 quadratic elements across have 6 bilinear ones' 7 node lines,
// so the same per-configuration cost (docs/model.md, "Quadratic elements").
void BM_SensorProfileFastRztMesh(benchmark::State& state) {
  SensorOptions options = TheoryOptions(combabc::plate::PlateTheory::kRzt);
  options.element_order = static_cast<int>(state.range(0));
  options.elements_per_section = static_cast<int>(state.range(1));
  options.elements_across_width = static_cast<int>(state.range(2));
  const SensorModel model{options};
  ProfileLoop(state, model);
}
BENCHMARK(BM_SensorProfileFastRztMesh)
    ->Args({1, 10, 6})
    ->Args({1, 20, 12})
    ->Args({2, 5, 3})
    ->Args({2, 10, 6})
    ->Unit(benchmark::kMicrosecond);
void BM_SensorProfileFullSolveRzt(benchmark::State& state) {
  SensorProfileFullSolve(state, combabc::plate::PlateTheory::kRzt);
}
BENCHMARK(BM_SensorProfileFullSolveRzt)->Unit(benchmark::kMillisecond);

// Continuous unknowns (SensorModel::Profile with a SensorVariation): every call has its own
// foundation stiffness, stiffness scale and (unless `own_loss`) loss factor, drawn over ranges a
// calibration would explore, so no two calls share values. The continuous precompute is built
// before timing starts (BM_SensorVariationPrecompute times it).
std::vector<combabc::plate::SensorVariation> Variations(int count, bool own_loss, double scale_lo) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<combabc::plate::SensorVariation> all(count);
  for (auto& v : all) {
    v.foundation_stiffness = 1e4 * std::pow(20.0, unit(rng));  // 1e4 .. 2e5 N/m^3
    v.stiffness_scale = scale_lo * std::pow(4.0, unit(rng));   // scale_lo .. 4 scale_lo
    if (!own_loss) v.loss_factor = 0.02 + 0.3 * unit(rng);
  }
  return all;
}

void RunVariation(benchmark::State& state,
                  const SensorModel& model,
                  bool own_loss,
                  double scale_lo) {
  const auto configs = Configurations(256, model.num_clamps());
  const auto variations = Variations(256, own_loss, scale_lo);
  std::vector<double> out(model.num_outputs());
  model.Profile(configs[0], variations[0], out);  // builds the precompute
  std::size_t i = 0;
  for (auto _ : state) {
    model.Profile(configs[i % configs.size()], variations[i % variations.size()], out);
    ++i;
    benchmark::DoNotOptimize(out.data());
  }
  const auto terms = model.VariationSeriesTerms(variations[0]);
  state.counters["series_terms"] = terms[0];
  state.counters["precomputed_MiB"] =
      static_cast<double>(model.VariationPrecomputedBytes()) / (1024.0 * 1024.0);
}

// k_f, s and eta per call: the series path (|mu| / lambda_1 < 0.01 here, 5-8 terms).
void BM_SensorProfileVariation(benchmark::State& state) {
  RunVariation(state, DefaultModel(), false, 0.5);
}
BENCHMARK(BM_SensorProfileVariation)->Unit(benchmark::kMicrosecond);

// k_f and s per call with the layers' own loss factors, on a laminate whose damping is not
// proportional (the core's Poisson ratio differs), so K_base is complex. (For the default
// laminate the layers' own damping is proportional and this is the case above.)
void BM_SensorProfileVariationOwnLoss(benchmark::State& state) {
  static const SensorModel model = [] {
    SensorOptions o;
    o.layers[1].poisson_ratio = 0.3;
    return SensorModel(o);
  }();
  RunVariation(state, model, true, 0.5);
}
BENCHMARK(BM_SensorProfileVariationOwnLoss)->Unit(benchmark::kMicrosecond);

// A laminate 1000 times softer (s in [1e-3, 4e-3]): |mu| / lambda_1 > 0.3, every state condensed
// directly per call (the exact fallback of the series).
void BM_SensorProfileVariationDirect(benchmark::State& state) {
  RunVariation(state, DefaultModel(), false, 1e-3);
}
BENCHMARK(BM_SensorProfileVariationDirect)->Unit(benchmark::kMicrosecond);

// Building the continuous precompute (one loss-factor kind) on top of a built model.
void BM_SensorVariationPrecompute(benchmark::State& state) {
  const auto configs = Configurations(1, 36);
  const auto variations = Variations(1, false, 0.5);
  std::vector<double> out(91);
  for (auto _ : state) {
    state.PauseTiming();
    SensorModel model{SensorOptions{}};
    state.ResumeTiming();
    model.Profile(configs[0], variations[0], out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_SensorVariationPrecompute)->Unit(benchmark::kMillisecond);

// Threaded batch with a variation per configuration; items/s is configurations per second.
void BM_SensorProfileVariationBatch(benchmark::State& state) {
  const SensorModel& model = DefaultModel();
  const int n = 256;
  const auto configs = Configurations(n, model.num_clamps());
  const auto variations = Variations(n, false, 0.5);
  std::vector<std::uint8_t> flat;
  for (const auto& c : configs) flat.insert(flat.end(), c.begin(), c.end());
  std::vector<double> out(static_cast<std::size_t>(n) * model.num_outputs());
  const int threads = static_cast<int>(state.range(0));
  model.ProfileBatch(flat, variations, n, out, threads);  // builds the precompute
  for (auto _ : state) {
    model.ProfileBatch(flat, variations, n, out, threads);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_SensorProfileVariationBatch)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

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
