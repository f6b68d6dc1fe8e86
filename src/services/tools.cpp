// The non-sampling jobs: simulate one configuration, export a history (the report: report.cpp).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/export/export.hpp"
#include "combabc/services/calibration.hpp"
#include "services/simulator_factory.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

std::string Sibling(const std::string& history_path, const std::string& name) {
  const auto parent = fs::path(history_path).parent_path();
  return (parent.empty() ? fs::path(name) : parent / name).string();
}

}  // namespace

void SimulateConfiguration(const std::string& config_path,
                           const std::string& clamps,
                           const std::string& output_csv,
                           bool overwrite) {
  auto config = LoadConfig(config_path);
  const bool sensor = config.simulator.kind == SimulatorKind::kSensor;
  // The nominal model: the sensor at its [model] values; an external simulator would need values
  // for its continuous parameters, which this command does not take.
  if (!config.reals.empty() && !sensor) {
    throw Error(ErrorKind::kUsage,
                "the simulator has continuous parameters ([parameters]); 'combabc simulate' "
                "takes only the bits",
                config_path);
  }
  config.reals.clear();
  // The sensor's raw amplitude in metres; the normalised column is derived below.
  config.model.normalise = false;
  const int dimension = config.space.dimension;  // checked before the costly precompute
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
  // A unique temporary beside the target, renamed at the end: no partial CSV, nothing followed,
  // and an existing file refused before the precompute rather than after it.
  AtomicFile out(output_csv, overwrite);
  const fs::path csv(output_csv);
  const BuiltSimulator built = MakeSimulator(
      config, (csv.parent_path() / (csv.stem().string() + ".simulate.work")).string());
  const SimulatorOutputs& outputs = config.simulator.outputs;
  std::vector<double> w(static_cast<std::size_t>(outputs.size()));
  RandomStream rng(config.smc.seed, 0, 0);
  const std::vector<double> no_reals;
  try {
    built.simulator->Simulate({bits, no_reals}, rng, w);
  } catch (const SimulationFailed& e) {
    throw Error(
        ErrorKind::kSoftware, std::string("the simulation failed: ") + e.what(), config_path);
  }
  double peak = 0.0;
  for (double v : w) peak = std::max(peak, std::abs(v));

  out.out().precision(10);
  // The sensor's values are metres; an external simulator's are in its own unit.
  out.out() << "position_m," << outputs.name << (sensor ? "_m" : "") << ",normalised\n";
  for (std::size_t i = 0; i < w.size(); ++i) {
    out.out() << outputs.coordinates[i] << ',' << w[i] << ',' << (peak > 0 ? w[i] / peak : 0.0)
              << '\n';
  }
  out.Commit();
}

VerifyOutcome VerifyHistory(const std::string& history_path) {
  const HistoryCheck check = HistoryStore::Verify(history_path);
  VerifyOutcome outcome;
  outcome.ok = check.problems.empty();
  if (!outcome.ok) {
    outcome.lines = check.problems;
    return outcome;
  }
  const std::string waves = std::to_string(check.waves) + (check.waves == 1 ? " wave" : " waves");
  outcome.lines.push_back(history_path + ": OK (" + waves +
                          (check.checksummed
                               ? ", checksums verified)"
                               : "; no checksums (schema v" + std::to_string(check.schema_version) +
                                     "): structure checked only)"));
  return outcome;
}

std::string ExportHistory(const std::string& history_path,
                          const std::string& directory,
                          bool overwrite) {
  std::string out = directory.empty() ? Sibling(history_path, "export") : directory;
  ExportOptions options;
  options.overwrite = overwrite;
  ExportRun(history_path, out, options);
  return out;
}

}  // namespace combabc::services
