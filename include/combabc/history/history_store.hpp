#pragma once
// The run history on disk: one SQLite file per run (RUN.sqlite), written batch by batch while the
// run goes, so that a killed run can be resumed and a finished one reported or exported. The
// schema, its version and the durability guarantees are documented in docs/history.md.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>
#include "combabc/core/enum_names.hpp"

#include "combabc/distances/distance.hpp"
#include "combabc/params/continuous_prior.hpp"
#include "combabc/proposals/proposal_options.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc {

// Version of the on-disk schema this build writes; it reads this version and older ones.
// Version 2 added checksums and each wave's overshoot; version 3 the continuous parameters (their
// priors, each particle's values, each wave's means and sds), the proposal options and the run's
// fingerprint; version 4 the failed simulations (table failure, each wave's failure count);
// version 5 the number of wave rows (meta row wave_count, under the run state's checksum);
// version 6 the experiments (table experiment); version 7 the multi-fidelity columns (each
// particle's multiplier, confirmed and low_distance, each wave's continuation probabilities and
// costs), NULL in a single-fidelity run; version 8 each wave's pattern classes (the mode-loss
// diagnostic: pattern_bits, pattern_mass, pattern_proposal, pattern_flagged), NULL for none;
// version 9 classes of one or two bits' values (pattern_bits then holds each class's bits and its
// mask; no new column); version 10 resample-move waves (each wave's move statistics, move_*, and
// each particle's ancestor), NULL in a rejection wave and for a particle drawn afresh. An older
// file written to (resume) is upgraded to this version.
inline constexpr int kHistorySchemaVersion = 10;

enum class RunStatus {
  kRunning,      // being written, or killed before it could say otherwise
  kFinished,     // the run ended by one of its own termination criteria
  kFailed,       // the run stopped on an error (message in RunMetadata::summary_message)
  kInterrupted,  // stopped on request (Ctrl-C); resumable
};
template <>
struct EnumNames<RunStatus> {
  static constexpr std::pair<RunStatus, const char*> kNames[] = {
      {RunStatus::kRunning, "running"},
      {RunStatus::kFinished, "finished"},
      {RunStatus::kFailed, "failed"},
      {RunStatus::kInterrupted, "interrupted"},
  };
};

// The measured data Y, kept so that reports can draw it over the accepted curves.
struct StoredMeasuredData {
  std::vector<double> positions;  // same unit as RunMetadata::position_unit
  std::vector<double> values;
};

// One experiment of the run (docs/config.md, "Experiments"), as slices of RunMetadata's
// concatenated output_positions, measured data and distance_components, in experiment order.
// Schema v6; an older file reads as one unnamed experiment holding everything.
struct StoredExperiment {
  std::string name;         // "" for the single experiment of a config without [[experiment]]
  std::string description;  // its load and scan, for reports ("load at 0.45 m, ...")
  int outputs = 0;          // output_positions of this experiment
  int measured = 0;         // measured points of this experiment
  int components = 0;       // distance components of this experiment
};

// Everything about a run except its waves: provenance, problem description, status and summary.
struct RunMetadata {
  // Provenance.
  std::string config_text;      // the whole TOML configuration, verbatim
  std::string config_path;      // where it was read from (may be empty)
  std::string combabc_version;  // empty = this library's version, filled in by Create
  std::string git_hash;         // may be empty
  std::uint64_t seed = 0;
  int threads = 1;
  std::string start_time;  // ISO 8601 UTC; empty = now, filled in by Create
  std::string end_time;    // set by Finish / MarkFailed

  // Status and outcome.
  RunStatus status = RunStatus::kRunning;
  std::string termination;      // termination criterion, e.g. "max_waves" (empty while running)
  std::string summary_message;  // RunSummary::message, or the error for a failed run
  int resume_count = 0;         // how many times the run was resumed

  // The problem, for reports.
  std::string estimator;  // "paper" or "importance"
  int dimension = 0;
  std::vector<std::string> bit_names;                  // empty or one per bit
  std::vector<double> bit_prior_one;                   // prior P(bit = 1); empty = 0.5 for all
  std::vector<DistanceComponent> distance_components;  // in component order
  std::vector<double> output_positions;                // x of each simulated output value
  std::string position_unit = "m";                     // unit of output and measured positions
  StoredMeasuredData measured;  // every experiment's points, experiment after experiment
  // Schema v6; empty before Create fills it (one experiment holding everything) and for older
  // files, which read as that one experiment.
  std::vector<StoredExperiment> experiments;
  // Schema v3; older files read as no reals, the default (independent) kernels and an empty
  // tempering form (not recorded).
  std::vector<ContinuousParameter> reals;  // the continuous parameters, in ParameterValue order
  ProposalOptions proposal;                // the kernels that proposed each wave
  std::string tempering_form;              // TemperingForm name, e.g. "geometric"
  // What makes the run reproducible, as (part, 16 hex digits) pairs, e.g. ("data", "0f3e...");
  // stored as meta rows fingerprint_<part>. Opaque to the history: the services layer computes
  // the parts and resume compares them (docs/history.md, "Fingerprint"). Empty before v3.
  std::vector<std::pair<std::string, std::string>> fingerprint;
  // The stop limits a resume set over the config's (`combabc resume --max-simulations` ...), as
  // (key, value) pairs by key, e.g. ("max_simulations", "20000"); stored as meta rows
  // stop_limit_<key>, covered by run_state_hash. Empty when no resume changed a limit.
  std::vector<std::pair<std::string, std::string>> stop_limits;

  int schema_version = kHistorySchemaVersion;  // as read from the file
};

// What HistoryStore::Verify found: every problem, one line each (none = the file is sound).
struct HistoryCheck {
  int schema_version = kHistorySchemaVersion;
  bool checksummed = true;  // false for schema v1, which had no checksums to verify
  int waves = 0;            // wave rows checked
  std::vector<std::string> problems;
};

// A run history file. Create() starts a new run; Open() reads or resumes an existing one. As an
// SmcObserver it records the run while RunCombinatorialSmc runs: each callback is one SQLite
// transaction, so a run killed at any moment loses at most the batch in flight.
// Errors are combabc::Error naming the file: kCantCreate (also: another process is writing the
// run), kNoInput, kData (not a history, corrupt, newer schema) or kIo (a write failed).
// Every read is checked: each vector against the run's metadata, and (schema v2) each wave and the
// metadata against their checksums; see docs/history.md, "Integrity".
class HistoryStore final : public SmcObserver {
 public:
  // Creates `path` (its directory must exist) with status "running". Refuses an existing file
  // unless `overwrite`. On failure no file is left behind.
  static HistoryStore Create(const std::string& path,
                             const RunMetadata& metadata,
                             bool overwrite = false);
  // Opens an existing history after SQLite's quick_check, the schema objects' check, the
  // metadata's checks and the set of waves'. read_only suits report/export: no write is
  // attempted, no lock taken. Otherwise (resume) the file is locked for this process until the
  // store is destroyed; the first write (BeginResume) upgrades an older file to this version.
  static HistoryStore Open(const std::string& path, bool read_only = false);
  // Checks everything, without stopping at the first problem: SQLite's integrity_check, the
  // metadata, every wave's vectors, particles and checksum. Throws only when the file cannot be
  // read as a run history at all (missing, not SQLite, not ours, newer schema).
  static HistoryCheck Verify(const std::string& path);

  HistoryStore(HistoryStore&& other) noexcept;
  HistoryStore& operator=(HistoryStore&& other) noexcept;
  ~HistoryStore() override;

  const std::string& path() const;
  RunMetadata LoadMetadata() const;

  // SmcObserver: OnWaveStart records the wave (again on resume: its progress is kept);
  // OnBatch appends the accepted particles and the wave's progress in one transaction; OnWaveEnd
  // records final statistics and normalised weights (particles it does not list are dropped).
  void OnWaveStart(const WaveRecord& wave) override;
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override;
  void OnWaveEnd(const WaveRecord& wave) override;

  // The committed state: complete waves in full, and the first incomplete wave (if any) as the
  // partial wave with its accepted particles and next_index.
  ResumePoint LoadResumePoint() const;
  // Ended waves, then the partial wave if any (its statistics are empty unless it ended), and the
  // run summary as recorded by Finish.
  RunHistory LoadHistory() const;

  // Before resuming: drops whatever lies beyond the resume point (waves after the partial one,
  // the partial wave's end-of-wave statistics), marks the run running again, counts the resume,
  // records `stop_limits` (RunMetadata::stop_limits; a key already there is replaced), and
  // returns the resume point.
  ResumePoint BeginResume(const std::vector<std::pair<std::string, std::string>>& stop_limits = {});
  // Records the summary and end time; status becomes finished, or interrupted for
  // Termination::kInterrupted. Leaves a single self-contained file (no -wal beside it).
  void Finish(const RunSummary& summary);
  // Records a failure (status failed) with its one-line message.
  void MarkFailed(const std::string& message);

 private:
  struct Impl;
  explicit HistoryStore(std::unique_ptr<Impl> impl);
  static HistoryStore OpenFile(const std::string& path, bool read_only, bool check);
  std::unique_ptr<Impl> impl_;
};

}  // namespace combabc
