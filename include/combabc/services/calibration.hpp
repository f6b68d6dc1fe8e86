#pragma once
// The entry layer (Stan's services/): what the CLI, the end-to-end tests and future bindings call.
// Each function does one user-level job end to end and reports through callbacks; errors are
// combabc::Error with the ErrorKind the CLI maps to a sysexits code.
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc::services {

struct RunRequest {
  std::string config_path;
  std::string output_directory;  // overrides [output] directory when not empty
  int threads = -1;              // overrides [sampler] threads when >= 0
  bool overwrite = false;        // replace an existing history file
  bool report = true;            // write the report when the run ends
};

struct RunOutcome {
  std::string history_path;
  std::string report_directory;  // empty when no report was written
  RunHistory history;
};

// `progress` sees every wave start, batch and wave end (the CLI's progress bar) and may interrupt.
RunOutcome RunCalibration(const RunRequest& request, SmcObserver* progress = nullptr);

// Continues an interrupted or killed run from its history file; the result equals an
// uninterrupted run's. A finished run is reported as such (kUsage).
RunOutcome ResumeCalibration(const std::string& history_path,
                             int threads = -1,
                             bool report = true,
                             SmcObserver* progress = nullptr);

// One clamp configuration ("0110..." with one character per clamp, 1 = fixed) through the
// config's sensor model, written as CSV (position_m, displacement, and the normalised profile).
void SimulateConfiguration(const std::string& config_path,
                           const std::string& clamps,
                           const std::string& output_csv);

// Figures (PNG, SVG) and index.html for a run, into `directory` (default: report/ beside the
// history). Returns the directory.
std::string WriteReport(const std::string& history_path, const std::string& directory = {});

// The result of `combabc verify`: one "OK" line, or one line per problem found.
struct VerifyOutcome {
  bool ok = true;
  std::vector<std::string> lines;
};

// Checks a history end to end (SQLite integrity_check, metadata, every wave's vectors and
// checksums; docs/history.md, "Integrity"). Throws only for a file that is not a readable history.
VerifyOutcome VerifyHistory(const std::string& history_path);

// CSV + JSON export (docs/history.md); default directory: export/ beside the history.
std::string ExportHistory(const std::string& history_path,
                          const std::string& directory = {},
                          bool overwrite = false);

}  // namespace combabc::services
