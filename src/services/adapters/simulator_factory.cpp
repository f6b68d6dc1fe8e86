#include "services/adapters/simulator_factory.hpp"

#include <filesystem>
#include <map>
#include <mutex>

#include "combabc/core/error.hpp"
#include "combabc/services/adapters/sensor_simulator.hpp"
#include "combabc/simulators/command_simulator.hpp"
#include "combabc/simulators/work_directory.hpp"
#include "combabc/simulators/worker_simulator.hpp"
#include "simulators/experiments_simulator.hpp"
#include "simulators/selected_outputs.hpp"

namespace combabc::services {
namespace fs = std::filesystem;

std::string WorkDirectoryOf(const std::string& history_path) {
  const fs::path history(history_path);
  return (history.parent_path() / (history.stem().string() + ".work")).string();
}

namespace {

// The program runs in its own folder: no path handed to it may be relative to combabc's.
std::string Absolute(const std::string& path) {
  std::error_code ec;
  return fs::absolute(path, ec).lexically_normal().string();
}

// A work folder held by every simulator that works in it: made when absent, removed (if empty)
// when the last holder goes. One object per folder, shared through a registry, so that neither
// the order in which the simulators are destroyed (one per experiment; the expensive and the
// cheap one, whose folder lies inside the expensive one's) nor which of them came first decides
// whether an empty folder stays behind; a folder that was there before is never removed.
struct HeldFolder {
  HeldFolder(std::shared_ptr<const HeldFolder> outer, const std::string& path)
      : parent(std::move(outer)), folder(path) {}
  std::shared_ptr<const HeldFolder> parent;  // the folder this one lies in: it goes after it
  WorkDirectory folder;
};

std::shared_ptr<const HeldFolder> HoldFolder(const std::string& path,
                                             std::shared_ptr<const HeldFolder> parent) {
  static std::mutex mutex;
  static std::map<std::string, std::weak_ptr<const HeldFolder>> held;
  const std::lock_guard<std::mutex> lock(mutex);
  std::erase_if(held, [](const auto& entry) { return entry.second.expired(); });
  std::weak_ptr<const HeldFolder>& slot = held[path];
  if (auto folder = slot.lock()) return folder;
  auto folder = std::make_shared<const HeldFolder>(std::move(parent), path);
  slot = folder;
  return folder;
}

std::unique_ptr<Simulator> MakeSensor(const CalibrationConfig& config,
                                      const std::vector<SensorModelPlan>& plans,
                                      const std::string& key,
                                      ThreadPool* threads) {
  std::vector<std::string> real_names;
  for (const auto& r : config.reals) real_names.push_back(r.name);
  plate::PrecomputeOptions precompute;
  precompute.pool = threads;
  precompute.cache_directory = plate::DefaultPrecomputeCache();
  auto sensor = std::make_unique<SensorSimulator>(plans, std::move(real_names), precompute);
  const int clamps = sensor->num_clamps();
  if (config.space.dimension != clamps) {
    throw Error(ErrorKind::kConfig,
                "the sampler has " + std::to_string(config.space.dimension) +
                    " bits; the model has " + std::to_string(clamps) + " clamps",
                config.path,
                0,
                key);
  }
  return sensor;
}

// A command or worker simulator (`simulator`: the config's [simulator] or its cheap one), one
// per experiment when the config has [[experiment]] tables, working in `folder`.
BuiltSimulator MakeExternal(const CalibrationConfig& config,
                            const SimulatorConfig& simulator,
                            std::shared_ptr<const HeldFolder> folder) {
  BuiltSimulator built;
  ExternalSimulatorOptions options = simulator.external;
  options.work_directory = folder->folder.path();
  built.folder = std::move(folder);
  std::error_code ec;
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
      if (simulator.kind == SimulatorKind::kCommand) {
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
    const bool cheap = &simulator != &config.simulator;
    const int line = e.field() == "simulator.argv" ? simulator.argv_line : 0;
    const std::string field = cheap && e.field() == "simulator.argv"
                                  ? std::string("simulator.low_fidelity.argv")
                                  : e.field();
    throw Error(e.kind(), e.message(), config.path, line, field);
  }
  return built;
}

}  // namespace

BuiltSimulator MakeSimulator(const CalibrationConfig& config,
                             const std::string& work_directory,
                             ThreadPool* threads) {
  if (config.simulator.kind == SimulatorKind::kSensor) {
    BuiltSimulator built;
    built.simulator = MakeSensor(config, SensorModels(config), "model", threads);
    return built;
  }
  return MakeExternal(config, config.simulator, HoldFolder(Absolute(work_directory), nullptr));
}

BuiltSimulator MakeLowFidelitySimulator(const CalibrationConfig& config,
                                        const std::string& work_directory,
                                        ThreadPool* threads) {
  BuiltSimulator built;
  if (!config.low_fidelity) return built;
  const LowFidelityConfig& low = *config.low_fidelity;
  if (low.simulator.kind == SimulatorKind::kSensor) {
    built.simulator =
        MakeSensor(config, LowFidelitySensorModels(config), "simulator.low_fidelity", threads);
  } else {
    // Its own folder inside the run's: its calls' folders must not meet the expensive ones'. The
    // run's folder is made here too, as the expensive simulator may be the sensor.
    const std::string run_folder = Absolute(work_directory);
    built = MakeExternal(config,
                         low.simulator,
                         HoldFolder((fs::path(run_folder) / "low_fidelity").string(),
                                    HoldFolder(run_folder, nullptr)));
  }
  bool identity = static_cast<int>(low.output_map.size()) == built.simulator->output_size();
  for (std::size_t k = 0; identity && k < low.output_map.size(); ++k) {
    identity = low.output_map[k] == static_cast<int>(k);
  }
  if (!identity) {
    built.simulator = std::make_unique<SelectedOutputs>(std::move(built.simulator), low.output_map);
  }
  return built;
}

}  // namespace combabc::services
