#pragma once
// The steps every run and resume shares, whoever built its problem (a config: RunCalibration,
// ResumeCalibration; the caller: RunProblem, the Python module's run and resume): the sampler
// with its history and report, the checks that decide whether a history may be continued, and
// the stop limits a resume sets. One copy, so that a rule added here holds for the CLI and for
// Python alike. Private to src/services.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "combabc/history/history_store.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/services/run.hpp"

namespace combabc::services {

// What Execute runs and where it stores it.
struct Execution {
  SmcProblem problem;  // its executor set
  const SmcOptions* options = nullptr;
  // The history on the primary; null on the other workers of a distributed executor, and for a
  // run that writes none (RunProblem without a path).
  HistoryStore* store = nullptr;
  std::string history_path;
  const ResumePoint* resume = nullptr;  // null: a new run
  bool report = false;
  ReportProgress report_progress;
  std::function<void(const FitChecks&)> on_checks_before;  // may be empty
};

// Runs the sampler, storing each batch on the primary, marks the history failed when it throws
// (and rethrows), finishes it and reads the checks and the answer back from it, then draws the
// report when asked.
RunOutcome Execute(const Execution& run, SmcObserver* progress);

// What a resume continues: a run that stopped on a limit, or finished all its waves and is given
// more (limits.num_waves); anything else unfinished (interrupted, killed, failed) goes on as it
// was. Throws Error(kUsage) naming `path` for a run that ended on its own otherwise, with the
// next step to take. Returns whether the run had finished (on a limit or its waves).
bool CheckResumable(const RunMetadata& metadata,
                    const StopLimits& limits,
                    OptionNames names,
                    const std::string& path);

// Sets `options`' stop limits from those an earlier resume recorded, then from `given`, and
// checks them; returns every limit set this way as (key, value) text, to record in the history.
std::vector<std::pair<std::string, std::string>> ApplyStopLimits(
    const std::vector<std::pair<std::string, std::string>>& recorded,
    const StopLimits& given,
    SmcOptions& options);

// Before anything is rewritten: a finished run (CheckResumable) whose limits, as applied, would
// stop it again at once is refused (kUsage) with the option to raise; a run that started from a
// finished one (a "start" fingerprint part) and stopped before its wave 0 was stored, too.
void CheckContinuation(const RunMetadata& metadata,
                       const SmcOptions& options,
                       bool finished,
                       OptionNames names,
                       const std::string& path);

// The resume point, taken by the primary's BeginResume (recording `limits`) and read by the other
// workers once it has (a distributed executor); `store` is null off the primary.
ResumePoint BeginResumeOnAll(Executor& executor,
                             HistoryStore* store,
                             const std::string& path,
                             const std::vector<std::pair<std::string, std::string>>& limits);

// The fingerprint part ("start", digest) a stored run has when it started from a finished one.
const std::pair<std::string, std::string>* StartPart(const RunMetadata& metadata);

}  // namespace combabc::services
