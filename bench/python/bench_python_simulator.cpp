// Engine overhead with a simulator written in Python (issue 11: <= 2 us per simulation with a
// vectorised batch callable, <= 20 us with a per-sample one, d = 10). The interpreter is embedded;
// the simulator is python/src/python_simulator.cpp, as `combabc.run(Problem(...))` uses it, and
// returns np.zeros, so that what is timed is the engine plus the Python calls. A distance written
// in Python (python/src/python_simulator.cpp, PythonDistance) is timed the same way: |output[0]|.
// With rng=True the simulator may draw its noise: batched, vectorised from the BatchRandom
// (python/src/batch_random.hpp) or candidate by candidate from the numpy Generators it holds.
#include <benchmark/benchmark.h>
#include <pybind11/embed.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "batch_random.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "python_call.hpp"
#include "python_distance.hpp"
#include "python_simulator.hpp"

namespace {

namespace py = pybind11;
using namespace combabc;
using combabc::python::FirstPythonError;
using combabc::python::PythonDistance;
using combabc::python::PythonSimulator;

constexpr int kBits = 10;
constexpr int kOutputs = 3;

class ZeroDistance : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"zero", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0]);
  }
};

// The class the simulator hands a batched function with rng=True, registered as combabc._core does.
PYBIND11_EMBEDDED_MODULE(combabc_bench, m) { combabc::python::BindBatchRandom(m); }

// range(0): 0 per sample, 1 vectorised batch; range(1): 1 with an rng it does not draw from (a
// numpy Generator per candidate; batched, a BatchRandom), 2 drawing three normal numbers per
// candidate from it (batched: rng.normal(size=3), vectorised), 3 (batched) drawing them from each
// candidate's numpy Generator (`for g in rng`); range(2): 1 with the distance written in Python
// too (per sample or batched as the simulator). One wave that accepts every candidate.
void BM_PythonSimulatorOverhead(benchmark::State& state) {
  const bool batch = state.range(0) == 1;
  const bool with_rng = state.range(1) >= 1;
  const char* const names[2][4] = {{"per_sample", "per_sample", "per_sample_normal", ""},
                                   {"batched", "batched", "batched_normal", "batched_generators"}};
  const char* const labels[4] = {"", ", rng", ", rng.normal(size=3)", ", Generator.normal(3) each"};
  const auto draws = static_cast<std::size_t>(state.range(1));
  const bool python_distance = state.range(2) == 1;
  const ParameterSpace space(BinarySpace::Independent(kBits));
  const ZeroDistance zero;
  SmcOptions options;
  options.num_waves = 1;
  options.accepted_per_wave = 20000;
  options.threads = 1;
  options.keep_outputs = false;
  FirstPythonError first_error;
  std::optional<PythonDistance> in_python;
  std::optional<PythonSimulator> simulator;
  {
    py::dict scope;
    scope["__builtins__"] = py::module_::import("builtins");
    py::exec(R"(
import numpy as np
def per_sample(bits, rng=None):
    return np.zeros(3)
def batched(bits, rng=None):
    return np.zeros((bits.shape[0], 3))
def per_sample_normal(bits, rng):
    return rng.normal(size=3)
def batched_normal(bits, rng):
    return rng.normal(size=3)
def batched_generators(bits, rng):
    return np.stack([g.normal(size=3) for g in rng])
def distance(output, observed):
    return abs(output[0])
def distance_batch(outputs, observed):
    return np.abs(outputs[:, 0])
class SimulationFailed(Exception):
    pass
)",
             scope);
    if (python_distance) {
      in_python.emplace(scope[batch ? "distance_batch" : "distance"],
                        batch,
                        std::vector<std::string>{},
                        std::vector<double>(kOutputs, 0.0),
                        scope["SimulationFailed"],
                        first_error);
    }
    simulator.emplace(scope[names[batch ? 1 : 0][draws]],
                      batch,
                      kOutputs,
                      0,
                      scope["SimulationFailed"],
                      with_rng,
                      first_error);
  }
  const Distance& distance = in_python ? static_cast<const Distance&>(*in_python) : zero;
  state.SetLabel(std::string(batch ? "batch" : "per sample") + labels[draws] +
                 (python_distance ? ", Python distance" : ""));
  std::int64_t simulations = 0;
  for (auto _ : state) {
    const py::gil_scoped_release release;  // the engine's threads take it per call, as in Python
    const RunHistory h = RunCombinatorialSmc({&space, &*simulator, &distance}, options);
    simulations += h.summary.simulations + h.summary.simulations_discarded;
  }
  state.SetItemsProcessed(simulations);
  state.counters["per_simulation"] = benchmark::Counter(
      static_cast<double>(simulations), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  simulator.reset();  // with the GIL held
  in_python.reset();
}
BENCHMARK(BM_PythonSimulatorOverhead)
    ->Args({0, 0, 0})
    ->Args({1, 0, 0})
    ->Args({0, 1, 0})
    ->Args({1, 1, 0})
    ->Args({0, 2, 0})
    ->Args({1, 2, 0})
    ->Args({1, 3, 0})
    ->Args({0, 0, 1})
    ->Args({1, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  try {
    const py::scoped_interpreter interpreter;
    py::module_::import("combabc_bench");  // registers BatchRandom
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
  } catch (const std::exception& e) {  // numpy missing, a Python error in the simulator
    std::fprintf(stderr, "bench_python_simulator: %s\n", e.what());
    return 1;
  }
}
