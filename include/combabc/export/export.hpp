#pragma once
// Export of a run history to plain files for pandas, MATLAB and spreadsheets: one CSV per table
// plus summary.json. Files and columns are documented in docs/history.md.
#include <string>

#include "combabc/history/history_store.hpp"

namespace combabc {

struct ExportOptions {
  bool csv = true;        // waves, marginals, particles, curves, positions, measured (.csv)
  bool json = true;       // summary.json: metadata and per-wave statistics
  bool particles = true;  // particles.csv (one row per accepted particle, can be large)
  bool curves = true;     // curves.csv + positions.csv, when the run stored outputs
  // Write into an existing out_dir that combabc did not write (no manifest), replacing only the
  // files of the same names; nothing else in it is ever removed.
  bool overwrite = false;
};

// Writes the files into out_dir under the rules of OutputDirectory (core/output_files.hpp): created
// if missing (its parent must exist); a previous export there (it has a manifest) is replaced file
// by file; a non-empty directory combabc did not write is refused unless options.overwrite. All
// files appear together at the end, so a failure leaves out_dir as it was. Throws combabc::Error:
// kCantCreate (out_dir refused, parent missing or not writable), kIo.
void ExportRun(const HistoryStore& store,
               const std::string& out_dir,
               const ExportOptions& options = {});
// Same, opening the history read-only first (kNoInput / kData as HistoryStore::Open).
void ExportRun(const std::string& history_path,
               const std::string& out_dir,
               const ExportOptions& options = {});

}  // namespace combabc
