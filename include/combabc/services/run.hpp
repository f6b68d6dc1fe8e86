#pragma once
// `combabc run` and `combabc resume`: a calibration by combinatorial ABC-SMC, and its
// continuation from the history it left. Like every header here (the entry layer, Stan's
// services/: one header per user job, what the CLI, the end-to-end tests and the Python module
// call), each function does one user-level job end to end and reports through callbacks; errors
// are combabc::Error with the ErrorKind the CLI maps to a sysexits code.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "combabc/export/answer.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/export/strip.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/services/executor_factory.hpp"
#include "combabc/services/report.hpp"

namespace combabc::services {

struct RunRequest {
  std::string config_path;
  // When not empty, the config's text, read in place of the file at config_path (which still
  // names it and sets its directory): a candidate model of a model choice (services/model_choice).
  std::string config_text;
  std::string output_directory;  // overrides [output] directory when not empty
  int threads = -1;              // overrides [sampler] threads when >= 0
  bool overwrite = false;        // replace an existing history file
  bool report = true;            // write the report (report/ beside the history) when it ends
  // Not empty: a finished run's history whose posterior this run starts from, adding the config's
  // other experiments to it (docs/algorithm.md, "Adding data to a finished run").
  std::string start_from;
  ExecutorFactory executor;  // empty: threads on this machine
  // Called with the history's path once it is known, before the history is created (the CLI
  // prepares the line it prints if mpirun ends the job; docs/mpi.md). May be empty.
  std::function<void(const std::string&)> on_history_path;
  // Called on the primary once the first wave has ended and is stored, before the next wave
  // starts, with the checks before sampling (ComputeBeforeChecks of the stored wave: the same
  // numbers as RunOutcome::checks). May be empty.
  std::function<void(const FitChecks&)> on_checks_before;
  // Hears how far the report is drawn (services/report.hpp), on the primary. May be empty.
  ReportProgress on_report_progress;
};

struct RunOutcome {
  std::string history_path;
  std::string report_directory;  // empty when no report was written
  RunHistory history;
  FitChecks checks;  // the fit and sanity checks (docs/history.md, "Checks"); primary only
  // The answer in numbers (docs/history.md, "The answer"); primary only, absent when the history
  // could not be read back (checks says why).
  std::optional<Answer> answer;
  // The sensor's strip (export/strip.hpp), printed with the answer; none for other simulators.
  std::optional<StripLayout> strip;
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
  // [sampler] waves: more waves for a run that finished them all above its target (max_waves).
  // The continuation equals one longer run (docs/history.md, "Resume").
  std::optional<int> num_waves;
};

// How messages name the options that raise a limit: `combabc resume`'s ("--max-simulations") or
// the Python keywords ("max_simulations=").
enum class OptionNames { kCli, kPython };

struct ResumeRequest {
  std::string history_path;
  int threads = -1;    // overrides the run's threads when >= 0
  bool report = true;  // write the report (report/ beside the history) when it ends
  StopLimits limits;   // recorded in the history; later resumes keep them
  OptionNames names = OptionNames::kCli;  // how messages name the limits' options
  ExecutorFactory executor;               // empty: threads on this machine
  // As RunRequest's, when the first wave ends during this resume (a run killed in it).
  std::function<void(const FitChecks&)> on_checks_before;
  ReportProgress on_report_progress;  // as RunRequest's
};

// Continues an interrupted or killed run, or one that stopped on a limit (budget, wall time,
// acceptance floor, failure ceiling), from its history file; the result equals an uninterrupted
// run's under the same limits. Refused (kUsage): a run that ended on its own (target, waves,
// enumeration), and a stopped run whose limits would stop it again before any simulation.
RunOutcome ResumeCalibration(const ResumeRequest& request, SmcObserver* progress = nullptr);

// The `combabc resume` option that raises the limit a run stopped on (e.g. "--max-simulations"
// for Termination::kBudgetExhausted; "--waves" for kMaxWaves), or its Python keyword.
std::string LimitOption(Termination stop, OptionNames names = OptionNames::kCli);

// A problem the caller built around a simulator it owns (combabc.run(problem, options): a
// simulator written in Python), run through the same steps as a config's run and resume: the
// same history, stop limits, fingerprint and report. Its functions cannot be fingerprinted: a
// resume is given the same ones again, and `calling` says how they are called.
struct ProblemRunRequest {
  SmcProblem problem;  // space, simulator, distance, low_fidelity; start is set from start_from
  SmcOptions options;  // a resume's stop limits come from `limits` and the history, as the CLI's
  std::vector<double> observed;  // the data the distance compares with, one per output
  // The outputs' coordinates (Problem(positions=...)), stored where the sensor's are, so that the
  // report draws the curves against them; empty: the outputs' indices (unit "index").
  std::vector<double> positions;
  std::string position_unit;  // with positions: their unit ("" if none was given)
  // How the simulator and distance are called (batch, rng, ...), fingerprinted as the simulator.
  std::vector<std::pair<std::string, std::string>> calling;
  std::string history_path;  // empty: nothing is written (no resume, start_from or report)
  bool overwrite = false;    // replace an existing history file
  bool resume = false;       // continue the history at history_path
  bool report = false;       // write the report (report/ beside the history) when it ends
  std::string start_from;    // not empty: a finished run whose posterior wave 0 starts from
  StopLimits limits;         // a resume's, as ResumeRequest's
  OptionNames names = OptionNames::kPython;
};

// The history path empty, the outcome holds the history as run (nothing is read back). Errors as
// RunCalibration's and ResumeCalibration's; a resume is refused (kUsage) for a config run's
// history and for other functions or options than the run's (the fingerprint).
RunOutcome RunProblem(const ProblemRunRequest& request, SmcObserver* progress = nullptr);

// The metadata RunProblem stores (its fingerprint included): the names a history of the problem
// would give, for a run that writes none.
RunMetadata DescribeProblem(const ProblemRunRequest& request);

// The fingerprint part every caller-built problem's history has, and no config run's: how a
// resume tells the two apart (`combabc resume` refuses it; it has no config to rebuild it from).
inline constexpr const char* kCallerProblemPart = "python_problem";

}  // namespace combabc::services
