// MPI parallel efficiency (issue 10: >= 90 % at 2 ranks with a 10 ms simulator). A Google
// Benchmark program meant to run under mpirun: every rank runs the same benchmark (fixed
// iterations, so that the ranks stay in step) through an MpiExecutor with one thread per rank;
// rank 0 reports. Efficiency = T(np 1) / (2 x T(np 2)) over the same runs (the same history):
//   mpirun -np 1 build/bench/bench_mpi_efficiency ; mpirun -np 2 build/bench/bench_mpi_efficiency
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "combabc/mpi/mpi_executor.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"

namespace {

using namespace combabc;

// Output = bits after a fixed 10 ms: asleep (an external simulator: the rank waits for it) or
// spinning (a simulator computing in-process; competes for the cores).
class TenMsSimulator : public Simulator {
 public:
  TenMsSimulator(int d, bool spin) : d_(d), spin_(spin) {}
  int output_size() const override { return d_; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    const auto cost = std::chrono::milliseconds(10);
    if (spin_) {
      const auto until = std::chrono::steady_clock::now() + cost;
      while (std::chrono::steady_clock::now() < until) {
      }
    } else {
      std::this_thread::sleep_for(cost);
    }
    for (int k = 0; k < d_; ++k) out[k] = theta.bits[k];
  }

 private:
  int d_;
  bool spin_;
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

// range(0): 0 sleep, 1 spin. 2 waves x 100 accepted at d = 36 (about 400 simulations, 4 s on one
// rank).
void BM_Mpi10msSimulator(benchmark::State& state) {
  const int d = 36;
  const ParameterSpace space(BinarySpace::Independent(d));
  TenMsSimulator sim(d, state.range(0) == 1);
  HammingDistance dist(d);
  mpi::MpiExecutor executor(1);
  SmcOptions options;
  options.num_waves = 2;
  options.accepted_per_wave = 100;
  options.thresholds.resize(1);  // adaptive median thresholds from eps_0 = inf
  SmcProblem problem{&space, &sim, &dist};
  problem.executor = &executor;
  std::int64_t candidates = 0;
  for (auto _ : state) {
    const auto h = RunCombinatorialSmc(problem, options);
    candidates += h.summary.simulations + h.summary.simulations_discarded;
  }
  state.SetLabel(std::string(state.range(0) == 1 ? "spin" : "sleep") + ", " +
                 std::to_string(executor.size()) + " rank(s)");
  state.counters["simulations_per_run"] =
      static_cast<double>(candidates) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_Mpi10msSimulator)
    ->Arg(0)
    ->Arg(1)
    ->Iterations(1)
    ->Repetitions(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Rank 0 alone prints.
class Silent : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>&) override {}
};

}  // namespace

int main(int argc, char** argv) {
  combabc::mpi::MpiSession session(&argc, &argv);
  benchmark::Initialize(&argc, argv);
  Silent silent;
  if (session.rank() == 0) {
    benchmark::RunSpecifiedBenchmarks();
  } else {
    benchmark::RunSpecifiedBenchmarks(&silent);
  }
  benchmark::Shutdown();
  return 0;
}
