#pragma once
// The entry layer (Stan's services/): what the CLI, the end-to-end tests and future bindings call.
// Each function does one user-level job end to end and reports through callbacks; errors are
// combabc::Error with the ErrorKind the CLI maps to a sysexits code.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/core/executor.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::services {

// Where the simulations run, made once the run's threads are known (the config's [sampler] threads
// or the override). Empty: a ThreadPoolExecutor. With a distributed executor (MPI) every worker
// calls the same service; only the executor's primary writes files, and every worker returns or
// throws alike (Executor::Join), so that all exit with the same code.
using ExecutorFactory = std::function<std::unique_ptr<Executor>(int threads)>;

struct RunRequest {
  std::string config_path;
  std::string output_directory;  // overrides [output] directory when not empty
  int threads = -1;              // overrides [sampler] threads when >= 0
  bool overwrite = false;        // replace an existing history file
  bool report = true;            // write the report (report/ beside the history) when it ends
  ExecutorFactory executor;      // empty: threads on this machine
  // Called with the history's path once it is known, before the history is created (the CLI
  // prepares the line it prints if mpirun ends the job; docs/mpi.md). May be empty.
  std::function<void(const std::string&)> on_history_path;
};

struct RunOutcome {
  std::string history_path;
  std::string report_directory;  // empty when no report was written
  RunHistory history;
};

// `progress` sees every wave start, batch and wave end (the CLI's progress bar) and may interrupt.
RunOutcome RunCalibration(const RunRequest& request, SmcObserver* progress = nullptr);

// Stop limits a resume sets over the run's config (docs/history.md, "Resume"); unset = as the run
// had them. Not part of the run's fingerprint: they decide where a run stops, not what it samples.
struct StopLimits {
  std::optional<std::int64_t> max_simulations;  // [smc] max_simulations
  std::optional<double> max_wall_time_s;        // [smc] max_wall_time
  std::optional<double> min_acceptance_rate;    // [smc] min_acceptance_rate
  std::optional<double> max_failure_fraction;   // [smc] max_failure_fraction
};

struct ResumeRequest {
  std::string history_path;
  int threads = -1;          // overrides the run's threads when >= 0
  bool report = true;        // write the report (report/ beside the history) when it ends
  StopLimits limits;         // recorded in the history; later resumes keep them
  ExecutorFactory executor;  // empty: threads on this machine
};

// Continues an interrupted or killed run, or one that stopped on a limit (budget, wall time,
// acceptance floor, failure ceiling), from its history file; the result equals an uninterrupted
// run's under the same limits. Refused (kUsage): a run that ended on its own (target, waves,
// enumeration), and a stopped run whose limits would stop it again before any simulation.
RunOutcome ResumeCalibration(const ResumeRequest& request, SmcObserver* progress = nullptr);

// The `combabc resume` option that raises the limit a run stopped on (e.g. "--max-simulations"
// for Termination::kBudgetExhausted).
std::string LimitOption(Termination stop);

struct EnumerateRequest {
  std::string config_path;
  std::string output_directory;    // overrides [output] directory when not empty
  int threads = -1;                // overrides [sampler] threads when >= 0
  bool overwrite = false;          // replace an existing history file
  bool report = true;              // write the report (report/ beside the history) when it ends
  std::vector<double> thresholds;  // one per threshold component; empty = the config's final ones
  int top = 20;                    // configurations in top_configurations.csv
  int max_particles = 100000;      // accepted configurations kept in the history (by mass)
  ExecutorFactory executor;        // empty: threads on this machine
};

struct EnumerateOutcome {
  std::string history_path;           // empty when interrupted (nothing is written)
  std::string enumeration_directory;  // RUN.enumeration/ beside the history
  std::string report_directory;       // empty when no report was written
  std::int64_t configurations = 0;
  std::int64_t enumerated = 0;
  std::int64_t accepted = 0;
  double evidence = 0.0;
  double wall_seconds = 0.0;
  bool interrupted = false;
};

// Exact ABC posterior of the config's problem at the given (or the config's final) thresholds by
// enumerating every free-bit configuration (docs/algorithm.md, "Exact enumeration"). Writes a
// history with one wave (termination "enumerated") that report and export read like any run, and
// pair_correlations.csv and top_configurations.csv into RUN.enumeration/ (OutputDirectory rules).
// An interrupted enumeration writes nothing: it has nothing to resume from. Without thresholds and
// without final ones in the config: Error kUsage.
EnumerateOutcome RunEnumeration(const EnumerateRequest& request, SmcObserver* progress = nullptr);

// The config's simulator at its nominal continuous values (the sensor at its [model] values; an
// external simulator without continuous parameters), as `combabc simulate` runs it; the Python
// module's SensorModel. Building it is the costly part (the sensor's precompute); Simulate may be
// called from several threads at once (Simulator's contract).
class NominalSimulator {
 public:
  // work_directory: where an external simulator makes its folders. A config whose external
  // simulator has continuous parameters is refused (kUsage).
  NominalSimulator(CalibrationConfig config, const std::string& work_directory);
  ~NominalSimulator();
  NominalSimulator(const NominalSimulator&) = delete;
  NominalSimulator& operator=(const NominalSimulator&) = delete;

  int dimension() const;
  int output_size() const { return static_cast<int>(positions().size()); }
  const std::vector<double>& positions() const;  // the outputs' coordinates (the sensor: metres)
  const std::string& output_name() const;        // the sensor: "displacement"
  bool is_sensor() const;
  const CalibrationConfig& config() const { return config_; }
  // One configuration's raw output (the sensor: |w| in metres along the centreline). A failed
  // simulation is Error kSoftware.
  std::vector<double> Simulate(std::span<const std::uint8_t> bits) const;
  // "0110..." (one character per bit) as bits, checked against the config: kUsage naming
  // --clamps.
  static std::vector<std::uint8_t> ParseBits(const CalibrationConfig& config,
                                             const std::string& clamps);
  std::vector<std::uint8_t> ParseBits(const std::string& clamps) const {
    return ParseBits(config_, clamps);
  }

 private:
  CalibrationConfig config_;
  std::unique_ptr<Simulator> simulator_;
};

// One bit configuration ("0110..." with one character per bit; for the sensor one per clamp,
// 1 = fixed) through the config's simulator at its nominal continuous values, written as CSV:
// position_m (the output coordinates), the output (the sensor's: displacement_m, raw metres) and
// the profile normalised by its largest magnitude; with [[experiment]] tables, every
// experiment's profile, each normalised by its own peak, after a column naming the experiment. An
// external simulator works in
// "<csv stem>.simulate.work" beside the CSV. An existing output_csv is refused (kCantCreate)
// unless `overwrite`.
void SimulateConfiguration(const std::string& config_path,
                           const std::string& clamps,
                           const std::string& output_csv,
                           bool overwrite = false);

// Figures (in the formats of the run's [output] figures) and index.html for a run, into
// `directory` (default: report/ beside the history), by scripts/report/combabc_report.py run with
// $COMBABC_PYTHON (default /usr/bin/python3); the script is the install's share/combabc/report/
// (relative to the binary, core/install_paths.hpp) unless $COMBABC_REPORT_SCRIPT names one. The
// directory follows OutputDirectory's rules (core/output_files.hpp): a previous report there is
// replaced, a non-empty directory combabc did not write is refused unless `overwrite`. A failure
// is one combabc::Error line. Returns the directory.
std::string WriteReport(const std::string& history_path,
                        const std::string& directory = {},
                        bool overwrite = false);

// The result of `combabc verify`: one "OK" line, or one line per problem found.
struct VerifyOutcome {
  bool ok = true;
  std::vector<std::string> lines;
};

// Checks a history end to end (SQLite integrity_check, metadata, every wave's vectors and
// checksums; docs/history.md, "Integrity"). Throws only for a file that is not a readable history.
VerifyOutcome VerifyHistory(const std::string& history_path);

struct ExportOutcome {
  std::string directory;
  std::string netcdf_path;  // empty when no NetCDF file was written
  std::string note;         // why not, when it was asked for but its Python packages are missing
};

// CSV + JSON export (docs/history.md); default directory: export/ beside the history; directory
// rules as for the report (`overwrite`: write into a directory combabc did not write). With
// `netcdf`, also inference_data.nc (ArviZ's InferenceData layout) by
// scripts/report/combabc_netcdf.py when $COMBABC_PYTHON (default /usr/bin/python3) has xarray and
// netCDF4; without them the rest is written and `note` says so.
ExportOutcome ExportHistory(const std::string& history_path,
                            const std::string& directory = {},
                            bool overwrite = false,
                            bool netcdf = true);

}  // namespace combabc::services
