#pragma once
// What every simulator declares to the workflow (its outputs), and the options of the external
// simulators: a program run once per candidate (CommandSimulator) or long-lived worker processes
// speaking a line protocol (WorkerSimulator). docs/simulators.md specifies both contracts.
#include <optional>
#include <string>
#include <vector>

#include "combabc/core/enum_names.hpp"
#include "combabc/core/validation_error.hpp"

namespace combabc {

// The simulator behind a run: the built-in plate sensor or an external program.
enum class SimulatorKind { kSensor, kCommand, kWorker };
template <>
struct EnumNames<SimulatorKind> {
  static constexpr std::pair<SimulatorKind, const char*> kNames[] = {
      {SimulatorKind::kSensor, "sensor"},
      {SimulatorKind::kCommand, "command"},
      {SimulatorKind::kWorker, "worker"},
  };
};

// The simulator's output vector Y*: one value per coordinate. Metric windows, measured-data
// interpolation, the history and the report all work in these coordinates.
struct SimulatorOutputs {
  std::string name = "displacement";  // what each value is, for reports
  std::vector<double> coordinates;    // metres (e.g. the sensor's laser positions), increasing
  int size() const { return static_cast<int>(coordinates.size()); }
};

// How a command simulator receives a candidate and hands back its outputs.
enum class Transport { kFile, kStdin, kStdout };
template <>
struct EnumNames<Transport> {
  static constexpr std::pair<Transport, const char*> kNames[] = {
      {Transport::kFile, "file"},
      {Transport::kStdin, "stdin"},
      {Transport::kStdout, "stdout"},
  };
};
enum class DataFormat { kJson, kCsv };
template <>
struct EnumNames<DataFormat> {
  static constexpr std::pair<DataFormat, const char*> kNames[] = {
      {DataFormat::kJson, "json"},
      {DataFormat::kCsv, "csv"},
  };
};

// Largest output (stdout, results file, one protocol line) read from an external simulator.
inline constexpr std::size_t kMaxSimulatorOutputBytes = std::size_t{16} << 20;  // 16 MiB

// The experiment a call simulates (docs/simulators.md, "Experiments"): sent with each request
// and available as argv placeholders, so that one program can simulate every experiment.
struct SimulatorExperiment {
  std::string name;
  double load_x = 0.0;           // m
  double load_y_fraction = 0.5;  // of the width
  double load_force = 0.0;       // N
  double frequency_hz = 0.0;
};

struct ExternalSimulatorOptions {
  // The program and its arguments, run without a shell. Placeholders replaced inside each
  // argument: {params} (the parameters file), {output} (the results file), {workdir} (the call's
  // or the worker's working directory), {config_dir} (the config file's directory).
  std::vector<std::string> argv;
  std::string config_directory;  // what {config_dir} stands for
  // Where per-call (command) or per-worker directories are made: created when absent, removed
  // at the end when combabc created it and it is empty.
  std::string work_directory;
  std::vector<std::string> bit_names;   // one per binary parameter, in order
  std::vector<std::string> real_names;  // the continuous parameters, in order
  int output_size = 0;
  double timeout_s = 60.0;  // per call (command) or per request (worker); 0 = none
  int retries = 0;          // further attempts after a failed one before the candidate fails
  // Command simulator only.
  Transport params = Transport::kFile;  // kFile ({params} in argv) or kStdin
  DataFormat params_format = DataFormat::kJson;
  Transport results = Transport::kStdout;  // kStdout or kFile ({output} in argv)
  DataFormat results_format = DataFormat::kCsv;
  // Set for a run with [[experiment]] tables: the experiment this simulator's calls are for.
  std::optional<SimulatorExperiment> experiment;
  // Worker simulator only: time for a new worker to print its handshake.
  double startup_timeout_s = 60.0;

  // On failure `error` names the field (owner "ExternalSimulatorOptions") and the constraint.
  bool IsValid(SimulatorKind kind, ValidationError* error) const;
  // The same as one sentence: "ExternalSimulatorOptions::argv is empty; name the program".
  bool IsValid(SimulatorKind kind, std::string* why) const;
};

// argv with the placeholders replaced, literally (no quoting, no expansion: there is no shell).
// With an experiment also {experiment} (its name), {load_x} (m), {load_y_fraction},
// {load_amplitude} (N) and {frequency} (Hz); without one those stay as written (the config
// refuses them without [[experiment]] tables).
std::vector<std::string> ExpandArgv(const std::vector<std::string>& argv,
                                    const std::string& params,
                                    const std::string& output,
                                    const std::string& workdir,
                                    const std::string& config_dir,
                                    const SimulatorExperiment* experiment = nullptr);
// The placeholders an experiment fills in, for the config's check.
inline constexpr const char* kExperimentPlaceholders[] = {
    "{experiment}", "{load_x}", "{load_y_fraction}", "{load_amplitude}", "{frequency}"};

}  // namespace combabc
