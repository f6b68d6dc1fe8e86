// `combabc simulate`: one configuration through the config's simulator at its nominal values.
#include "combabc/services/simulate.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "services/adapters/simulator_factory.hpp"

namespace combabc::services {
namespace fs = std::filesystem;

namespace {

// Whether the simulator `combabc simulate` runs is the sensor; a config without the cheap
// simulator asked for is refused (kUsage, naming --low-fidelity).
bool RunsSensor(const CalibrationConfig& config, bool low_fidelity) {
  if (low_fidelity && !config.low_fidelity) {
    throw Error(ErrorKind::kUsage,
                "--low-fidelity: the config has no cheap simulator ([simulator.low_fidelity])",
                config.path);
  }
  const SimulatorKind kind =
      low_fidelity ? config.low_fidelity->simulator.kind : config.simulator.kind;
  return kind == SimulatorKind::kSensor;
}

}  // namespace

NominalSimulator::NominalSimulator(CalibrationConfig config,
                                   const std::string& work_directory,
                                   bool low_fidelity)
    : config_(std::move(config)), sensor_(RunsSensor(config_, low_fidelity)) {
  const bool sensor = sensor_;
  // The nominal model: the sensor at its [model] values; an external simulator would need values
  // for its continuous parameters, which are not given here.
  if (!config_.reals.empty() && !sensor) {
    throw Error(ErrorKind::kUsage,
                "the simulator has continuous parameters ([parameters]); 'combabc simulate' "
                "takes only the bits",
                config_.path);
  }
  config_.reals.clear();
  // The sensor's raw amplitude in metres.
  config_.model.normalise = false;
  if (config_.low_fidelity) config_.low_fidelity->model.normalise = false;
  // The cheap simulator's outputs are those that stand for the expensive one's: the same
  // coordinates.
  BuiltSimulator built = low_fidelity ? MakeLowFidelitySimulator(config_, work_directory)
                                      : MakeSimulator(config_, work_directory);
  work_folder_ = std::move(built.folder);
  simulator_ = std::move(built.simulator);
}

NominalSimulator::~NominalSimulator() = default;

int NominalSimulator::dimension() const { return config_.space.dimension; }

const std::vector<double>& NominalSimulator::positions() const {
  return config_.simulator.outputs.coordinates;
}

const std::string& NominalSimulator::output_name() const { return config_.simulator.outputs.name; }

bool NominalSimulator::is_sensor() const { return sensor_; }

std::vector<std::uint8_t> NominalSimulator::ParseBits(const CalibrationConfig& config,
                                                      const std::string& clamps) {
  const bool sensor = config.simulator.kind == SimulatorKind::kSensor;
  const int dimension = config.space.dimension;
  if (static_cast<int>(clamps.size()) != dimension) {
    throw Error(ErrorKind::kUsage,
                "has " + std::to_string(clamps.size()) + " characters; the " +
                    (sensor ? "model has " + std::to_string(dimension) +
                                  " clamps (one 0/1 per clamp, 1 = fixed)"
                            : "simulator has " + std::to_string(dimension) +
                                  " bits (one 0/1 per bit, in [simulator.bits] order)"),
                "",
                0,
                "--clamps");
  }
  std::vector<std::uint8_t> bits(clamps.size());
  for (std::size_t k = 0; k < clamps.size(); ++k) {
    if (clamps[k] != '0' && clamps[k] != '1') {
      throw Error(ErrorKind::kUsage,
                  "character " + std::to_string(k + 1) + " is " + Excerpt(clamps.substr(k, 1)) +
                      "; must be 0 or 1",
                  "",
                  0,
                  "--clamps");
    }
    bits[k] = clamps[k] == '1';
  }
  return bits;
}

std::vector<double> NominalSimulator::Simulate(std::span<const std::uint8_t> bits) const {
  std::vector<double> out(static_cast<std::size_t>(simulator_->output_size()));
  if (static_cast<int>(bits.size()) != dimension()) {
    throw Error(ErrorKind::kUsage,
                "has " + std::to_string(bits.size()) + " bits; the simulator has " +
                    std::to_string(dimension()),
                "",
                0,
                "clamps");
  }
  // The sensor draws nothing; an external simulator gets the config's seed, as in a run's first
  // candidate stream.
  RandomStream rng(config_.smc.seed, 0, 0);
  const std::vector<double> no_reals;
  try {
    simulator_->Simulate({bits, no_reals}, rng, out);
  } catch (const SimulationFailed& e) {
    throw Error(e.kind(), std::string("the simulation failed: ") + e.what(), config_.path);
  }
  return out;
}

void SimulateConfiguration(const std::string& config_path,
                           const std::string& clamps,
                           const std::string& output_csv,
                           bool overwrite,
                           bool low_fidelity) {
  CalibrationConfig config = LoadConfig(config_path);
  const bool sensor = RunsSensor(config, low_fidelity);
  // Checked before the costly precompute.
  if (!config.reals.empty() && !sensor) {
    throw Error(ErrorKind::kUsage,
                "the simulator has continuous parameters ([parameters]); 'combabc simulate' "
                "takes only the bits",
                config_path);
  }
  const std::vector<std::uint8_t> bits = NominalSimulator::ParseBits(config, clamps);
  // A unique temporary beside the target, renamed at the end: no partial CSV, nothing followed,
  // and an existing file refused before the precompute rather than after it.
  AtomicFile out(output_csv, overwrite);
  const fs::path csv(output_csv);
  const NominalSimulator simulator(
      std::move(config),
      (csv.parent_path() / (csv.stem().string() + ".simulate.work")).string(),
      low_fidelity);
  const std::vector<double> w = simulator.Simulate(bits);
  const std::vector<double>& x = simulator.positions();
  const std::vector<ExperimentConfig>& experiments = simulator.config().experiments;
  // Named experiments get a column of their own, and each is normalised by its own peak.
  const bool named = experiments.front().line != 0;
  out.out().precision(10);
  // The sensor's values are metres; an external simulator's are in its own unit.
  out.out() << (named ? "experiment," : "") << "position_m," << simulator.output_name()
            << (sensor ? "_m" : "") << ",normalised\n";
  std::size_t begin = 0;
  for (const ExperimentConfig& e : experiments) {
    const std::size_t end = begin + e.output_coordinates.size();
    double peak = 0.0;
    for (std::size_t i = begin; i < end; ++i) peak = std::max(peak, std::abs(w[i]));
    for (std::size_t i = begin; i < end; ++i) {
      if (named) out.out() << e.name << ',';
      out.out() << x[i] << ',' << w[i] << ',' << (peak > 0 ? w[i] / peak : 0.0) << '\n';
    }
    begin = end;
  }
  out.Commit();
}

}  // namespace combabc::services
