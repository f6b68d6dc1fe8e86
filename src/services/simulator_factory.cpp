#include "services/simulator_factory.hpp"

#include <filesystem>

#include "combabc/core/error.hpp"
#include "combabc/services/sensor_simulator.hpp"
#include "combabc/simulators/command_simulator.hpp"
#include "combabc/simulators/worker_simulator.hpp"
#include "services/experiments_simulator.hpp"

namespace combabc::services {
namespace fs = std::filesystem;

std::string WorkDirectoryOf(const std::string& history_path) {
  const fs::path history(history_path);
  return (history.parent_path() / (history.stem().string() + ".work")).string();
}

BuiltSimulator MakeSimulator(const CalibrationConfig& config,
                             const std::string& work_directory,
                             ThreadPool* threads) {
  BuiltSimulator built;
  if (config.simulator.kind == SimulatorKind::kSensor) {
    std::vector<std::string> real_names;
    for (const auto& r : config.reals) real_names.push_back(r.name);
    plate::PrecomputeOptions precompute;
    precompute.pool = threads;
    precompute.cache_directory = plate::DefaultPrecomputeCache();
    auto sensor =
        std::make_unique<SensorSimulator>(SensorModels(config), std::move(real_names), precompute);
    const int clamps = sensor->num_clamps();
    if (config.space.dimension != clamps) {
      throw Error(ErrorKind::kConfig,
                  "the sampler has " + std::to_string(config.space.dimension) +
                      " bits; the model has " + std::to_string(clamps) + " clamps",
                  config.path,
                  0,
                  "model");
    }
    built.simulator = std::move(sensor);
    return built;
  }
  ExternalSimulatorOptions options = config.simulator.external;
  // The program runs in its own folder: no path handed to it may be relative to combabc's.
  std::error_code ec;
  options.work_directory = fs::absolute(work_directory, ec).lexically_normal().string();
  const fs::path dir = fs::absolute(config.directory.empty() ? "." : config.directory, ec);
  options.config_directory = dir.lexically_normal().string();
  if (!options.config_directory.empty() && options.config_directory.back() == '/' &&
      options.config_directory.size() > 1) {
    options.config_directory.pop_back();
  }
  try {
    // With [[experiment]] tables, one simulator per experiment, each told which it simulates.
    std::vector<std::unique_ptr<Simulator>> parts;
    for (const ExperimentConfig& x : config.experiments) {
      ExternalSimulatorOptions one = options;
      if (x.line != 0) {
        one.experiment = SimulatorExperiment{
            x.name, x.load.load_x, x.load.load_y_fraction, x.load.load_force, x.frequency_hz};
      }
      if (config.simulator.kind == SimulatorKind::kCommand) {
        parts.push_back(std::make_unique<CommandSimulator>(std::move(one)));
      } else {
        auto worker = std::make_unique<WorkerSimulator>(std::move(one));
        // The same program for every experiment: its first handshake identifies it.
        if (built.handshake.empty()) built.handshake = worker->handshake();
        parts.push_back(std::move(worker));
      }
    }
    if (parts.size() == 1) {
      built.simulator = std::move(parts.front());
    } else {
      built.simulator = std::make_unique<ExperimentsSimulator>(std::move(parts));
    }
  } catch (const Error& e) {
    if (!e.file().empty()) throw;
    // The program itself (missing, or a worker that does not start) is the argv key's problem.
    const int line = e.field() == "simulator.argv" ? config.simulator.argv_line : 0;
    throw Error(e.kind(), e.message(), config.path, line, e.field());
  }
  return built;
}

}  // namespace combabc::services
