#pragma once
// Export of a run history to plain files for pandas, MATLAB and spreadsheets: one CSV per table
// plus summary.json. Files and columns are documented in docs/history.md.
#include <string>

#include "combabc/history/history_store.hpp"

namespace combabc {

struct ExportOptions {
  bool csv = true;         // waves, marginals, particles, curves, positions, measured (.csv)
  bool json = true;        // summary.json: metadata and per-wave statistics
  bool particles = true;   // particles.csv (one row per accepted particle, can be large)
  bool curves = true;      // curves.csv + positions.csv, when the run stored outputs
  bool overwrite = false;  // replace an existing out_dir
};

// Writes the files into out_dir (created; its parent must exist). Everything is written into a
// temporary sibling directory first and renamed at the end, so a failure leaves no half-written
// out_dir. Throws combabc::Error: kCantCreate (out_dir exists, parent not writable), kIo.
void ExportRun(const HistoryStore& store,
               const std::string& out_dir,
               const ExportOptions& options = {});
// Same, opening the history read-only first (kNoInput / kData as HistoryStore::Open).
void ExportRun(const std::string& history_path,
               const std::string& out_dir,
               const ExportOptions& options = {});

}  // namespace combabc
