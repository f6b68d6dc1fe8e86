#pragma once
// Export of a run history to plain files for pandas, MATLAB and spreadsheets: one CSV per table
// plus summary.json. Files and columns are documented in docs/history.md.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "combabc/core/output_files.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/export/campaign.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/export/strip.hpp"
#include "combabc/history/history_store.hpp"

namespace combabc {

struct ExportOptions {
  bool csv = true;        // the CSV files: waves, marginals, pair correlations, particles, ...
  bool json = true;       // summary.json: metadata, per-wave statistics and the answer
  bool particles = true;  // particles.csv (one row per accepted particle, can be large)
  bool curves = true;     // curves.csv + positions.csv, when the run stored outputs
  // Write into an existing out_dir that combabc did not write (no manifest), replacing only the
  // files of the same names; nothing else in it is ever removed.
  bool overwrite = false;
  // Where each bit acts, for summary.json's "answer" (export/answer.hpp): one per bit, or empty
  // (positions null). The services layer derives them from the run's config.
  std::vector<std::optional<BitPosition>> bit_positions;
  // summary.json's "strip" (export/strip.hpp): the sensor's plate, clamp sections, loads and scan
  // lines, from the run's config; none (null) for other simulators.
  std::optional<StripLayout> strip;
  // summary.json's "checks" (export/fit_checks.hpp): their options, with the stated noise of the
  // run's noise-aware components, which the services layer reads from the run's config.
  FitCheckOptions checks;
  // campaign.csv (export/campaign.hpp): which experiment decided which clamp, for a joint run of
  // the sensor, which the services layer computes from the run's config and data. None: no file.
  std::optional<CampaignView> campaign;
  // Called with the CSV and JSON files staged, before anything is committed: adds files made
  // from them (the NetCDF file, written by a script: services/history_tools.cpp). Empty: none.
  std::function<void(OutputDirectory&)> add_files;
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

// Bit b's name (from 0): RunMetadata::bit_names[b], or "bit k" counted from 1 when the run named
// none. The one name of a bit wherever the export layer writes one (particles.csv's columns,
// summary.json's bit_names, the answer), so that readers find one by the other.
std::string BitName(const RunMetadata& metadata, std::size_t b);

// The export's column names (docs/history.md, "Export"), shared with the Python module's
// DataFrames: eps_<component> (T_<component> for a likelihood component's temperature) per
// threshold slot, d_<component> per distance component, each name made column-safe ("least
// squares" -> "least_squares"). `count` values per row; when the metadata disagrees with it
// (an older file), the names fall back to eps_<k> / d_<k>.
std::vector<std::string> ThresholdColumns(const RunMetadata& metadata, std::size_t count);
std::vector<std::string> DistanceColumns(const RunMetadata& metadata, std::size_t count);

// One experiment of a run (RunMetadata::experiments) with where its slices start: its outputs are
// the columns y_<first_output> ... of curves.csv (rows of positions.csv), its measured points the
// rows first_measured ... of measured.csv, its distance components the d_ columns from
// first_component on.
struct ExperimentSlice {
  std::string name;  // "" for the single experiment of a config without [[experiment]]
  std::string description;
  std::size_t first_output = 0;
  std::size_t outputs = 0;
  std::size_t first_measured = 0;
  std::size_t measured = 0;
  std::size_t first_component = 0;
  std::size_t components = 0;
};

// The run's experiments in order. Metadata without experiments (built by hand, as the Python
// module's in-memory runs do), or whose counts do not add up to its outputs, measured points and
// components (a checked history never does), is one unnamed experiment holding everything.
std::vector<ExperimentSlice> ExperimentSlices(const RunMetadata& metadata);
// Whether the run's experiments have names (its config has [[experiment]] tables): then the
// export's positions.csv and measured.csv get an `experiment` column.
bool HasNamedExperiments(const RunMetadata& metadata);

}  // namespace combabc
