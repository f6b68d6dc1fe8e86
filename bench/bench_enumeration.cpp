// Exact enumeration of the left/right-tied 45 cm sensor (clamp k tied to k + 18: 2^18
// configurations) on 2 threads, through the service the CLI calls (docs/algorithm.md, "Exact
// enumeration"; target <= 60 s). One iteration: it takes seconds, and the simulations dominate.
// COMBABC_BENCH_THRESHOLD overrides the area threshold (default 0.07: 8192 of the 2^18 accepted, 5
// clamp pairs decided).
#include <unistd.h>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <benchmark/benchmark.h>

#include "combabc/services/enumerate.hpp"

namespace {

namespace fs = std::filesystem;

std::string TiedConfig() {
  std::ifstream in(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/area.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string config = text.str();
  std::string tie = "tie = [";
  for (int k = 1; k <= 18; ++k) {
    tie += (k > 1 ? ", [" : "[") + std::to_string(k) + ", " + std::to_string(k + 18) + "]";
  }
  tie += "]\n";
  const auto sampler = config.find("[sampler]\n");
  config.insert(sampler + 10, tie);
  const auto data = config.find("csv = \"data.csv\"");
  config.replace(data,
                 16,
                 "csv = \"" +
                     (fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/data.csv").string() +
                     "\"");
  return config;
}

void BM_EnumerateTiedSensor(benchmark::State& state) {
  const fs::path dir =
      fs::temp_directory_path() / ("combabc-bench-enumerate-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "tied.toml") << TiedConfig();
  combabc::services::EnumerateRequest request;
  request.config_path = (dir / "tied.toml").string();
  request.output_directory = (dir / "out").string();
  request.threads = 2;
  request.overwrite = true;
  request.report = false;
  const char* eps = std::getenv("COMBABC_BENCH_THRESHOLD");
  request.thresholds = {eps ? std::atof(eps) : 0.07};
  combabc::services::EnumerateOutcome outcome;
  for (auto _ : state) outcome = combabc::services::RunEnumeration(request);
  state.counters["configurations"] = static_cast<double>(outcome.configurations);
  state.counters["accepted"] = static_cast<double>(outcome.accepted);
  state.counters["evidence"] = outcome.evidence;
  state.counters["configs_per_s"] =
      static_cast<double>(outcome.configurations) / outcome.wall_seconds;
  if (!std::getenv("COMBABC_BENCH_KEEP")) fs::remove_all(dir);
}
BENCHMARK(BM_EnumerateTiedSensor)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
