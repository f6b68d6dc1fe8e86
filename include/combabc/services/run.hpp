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

#include "combabc/export/answer.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/export/strip.hpp"
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
};

struct ResumeRequest {
  std::string history_path;
  int threads = -1;          // overrides the run's threads when >= 0
  bool report = true;        // write the report (report/ beside the history) when it ends
  StopLimits limits;         // recorded in the history; later resumes keep them
  ExecutorFactory executor;  // empty: threads on this machine
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
// for Termination::kBudgetExhausted).
std::string LimitOption(Termination stop);

}  // namespace combabc::services
