#pragma once
// The tools that read a finished (or any) history: `combabc verify` and `combabc export`, and the
// answer that run, resume and enumerate print at their end.
#include <string>
#include <vector>

#include "combabc/export/answer.hpp"

namespace combabc::services {

// The result of `combabc verify`: one "OK" line, or one line per problem found.
struct VerifyOutcome {
  bool ok = true;
  std::vector<std::string> lines;
};

// Checks a history end to end (SQLite integrity_check, metadata, every wave's vectors and
// checksums; docs/history.md, "Integrity"). Throws only for a file that is not a readable history.
VerifyOutcome VerifyHistory(const std::string& history_path);

// The answer of a history in numbers (export/answer.hpp), the sensor's clamps placed by the run's
// config: what `combabc run`, `resume` and `enumerate` print at their end, and summary.json's
// "answer" (ExportHistory). Errors as HistoryStore::Open.
Answer ReadAnswer(const std::string& history_path);

struct ExportOutcome {
  std::string directory;
  std::string netcdf_path;  // empty when no NetCDF file was written
  // Why not, when it was asked for but its Python packages are missing; or why it has no
  // posterior group (the answer's wave has signed multi-fidelity weights).
  std::string note;
};

// CSV + JSON export (docs/history.md); default directory: export/ beside the history; directory
// rules as for the report (`overwrite`: write into a directory combabc did not write). With
// `netcdf`, also inference_data.nc (ArviZ's InferenceData layout) by
// scripts/report/combabc_netcdf.py when $COMBABC_PYTHON (default /usr/bin/python3) has xarray and
// netCDF4; without them the rest is written and `note` says so. `all_waves` adds every wave's
// resampled posterior to it (`combabc export --all-waves`).
ExportOutcome ExportHistory(const std::string& history_path,
                            const std::string& directory = {},
                            bool overwrite = false,
                            bool netcdf = true,
                            bool all_waves = false);

}  // namespace combabc::services
