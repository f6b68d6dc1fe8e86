#pragma once
// `combabc enumerate`: the exact ABC posterior of a config's problem by simulating every
// configuration of its free bits.
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "combabc/export/answer.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/export/strip.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/services/executor_factory.hpp"
#include "combabc/services/report.hpp"

namespace combabc::services {

struct EnumerateRequest {
  std::string config_path;
  // When not empty, the config's text, read in place of the file at config_path (a model choice's
  // candidate model), as RunRequest's.
  std::string config_text;
  // The folder of the enumeration's history, tables and report when not empty; by default the
  // folder enumeration/ inside [output] directory (beside, never on, `combabc run`'s history).
  std::string output_directory;
  int threads = -1;                // overrides [sampler] threads when >= 0
  bool overwrite = false;          // replace an existing history file
  bool report = true;              // write the report (report/ beside the history) when it ends
  std::vector<double> thresholds;  // one per threshold component; empty = the config's final ones
  int top = 20;                    // configurations in top_configurations.csv
  int max_particles = 100000;      // accepted configurations kept in the history (by mass)
  ExecutorFactory executor;        // empty: threads on this machine
  ReportProgress on_report_progress;  // as RunRequest's
};

struct EnumerateOutcome {
  std::string history_path;           // empty when interrupted (nothing is written)
  std::string enumeration_directory;  // the tables: RUN.enumeration/ beside the history
  std::string report_directory;       // empty when no report was written
  std::int64_t configurations = 0;
  std::int64_t enumerated = 0;
  std::int64_t accepted = 0;
  double evidence = 0.0;
  // log evidence, which does not underflow where a likelihood component's evidence would (-inf
  // when nothing was accepted).
  double log_evidence = -std::numeric_limits<double>::infinity();
  double wall_seconds = 0.0;
  bool interrupted = false;
  // The config has a cheap simulator ([simulator.low_fidelity]): the enumeration left it out
  // (it enumerates the expensive simulator).
  bool low_fidelity_ignored = false;
  // The fit and sanity checks of its one-wave history (docs/history.md, "Checks"); primary only.
  FitChecks checks;
  // The answer in numbers, exact (docs/history.md, "The answer"); as RunOutcome::answer.
  std::optional<Answer> answer;
  std::optional<StripLayout> strip;  // the sensor's strip, as RunOutcome::strip
};

// Exact ABC posterior of the config's problem at the given (or the config's final) thresholds by
// enumerating every free-bit configuration (docs/algorithm.md, "Exact enumeration"). Writes a
// history with one wave (termination "enumerated") that report and export read like any run, and
// pair_correlations.csv and top_configurations.csv into RUN.enumeration/ (OutputDirectory rules).
// An interrupted enumeration writes nothing: it has nothing to resume from. Without thresholds and
// without final ones in the config: Error kUsage.
EnumerateOutcome RunEnumeration(const EnumerateRequest& request, SmcObserver* progress = nullptr);

}  // namespace combabc::services
