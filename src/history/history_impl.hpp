#pragma once
// HistoryStore's state, shared by history_create.cpp (create, open), history_store.cpp (record),
// history_load.cpp (load, resume) and history_verify.cpp (checks). Private to src/history.
#include <optional>
#include <string>

#include "combabc/history/history_store.hpp"
#include "history/history_hash.hpp"
#include "history/history_lock.hpp"
#include "history/history_sqlite.hpp"

namespace combabc {

// 'CBAB' in the SQLite header's application_id: tells a combabc history from any other database.
inline constexpr int kHistoryApplicationId = 0x43424142;

// What every stored vector must measure, from the run's metadata.
struct HistoryShape {
  int dimension = 0;
  std::size_t components = 0;            // distance values per particle
  std::size_t threshold_components = 0;  // thresholds per wave
  std::size_t outputs = 0;               // output values per particle, when kept
  std::size_t reals = 0;                 // continuous parameters (schema v3; 0 before)
  // Free parameters (proposal length): not in the metadata, so taken from wave 1's proposal,
  // which every later wave's must match. Waves are always read in order from the first.
  std::size_t free_parameters = 0;
  // The previous wave's candidates, which a particle's ancestor (v10) indexes; 0 before wave 1.
  std::int64_t previous_candidates = 0;
};

struct HistoryStore::Impl {
  Impl(const std::string& path, bool read_only_in, history::RunLock lock_in)
      : lock(std::move(lock_in)),
        db(path, /*create=*/false, read_only_in),
        read_only(read_only_in) {}

  // The writer's lock outlives the connection: closing the lock's descriptor while SQLite still
  // had the file open would drop SQLite's own locks (members are destroyed in reverse order). The
  // database outlives the statements prepared on it.
  history::RunLock lock;
  history::Database db;
  bool read_only = false;
  // Set by the first write (PrepareWrite): WAL mode on, an older file upgraded.
  bool write_ready = false;
  int schema_version = kHistorySchemaVersion;
  HistoryShape shape;
  std::optional<history::Statement> upsert_particle;
  std::optional<history::Statement> update_progress;
  std::optional<history::Statement> upsert_failure;

  // The checksum state of the wave being written: its particles so far, in candidate order.
  struct WaveChain {
    int wave = -1;
    std::int64_t next_candidate = 0;  // particles below this are in `hasher`
    std::int64_t next_failure = 0;    // failures below this are in `hasher`
    history::WaveHasher hasher;
  };
  WaveChain chain;

  bool checksummed() const { return schema_version >= 2; }
  bool has_reals() const { return schema_version >= 3; }
  bool has_failures() const { return schema_version >= 4; }
  bool has_wave_count() const { return schema_version >= 5; }
  bool has_experiments() const { return schema_version >= 6; }
  bool has_multi_fidelity() const { return schema_version >= 7; }
  bool has_pattern_classes() const { return schema_version >= 8; }
  bool has_pattern_masks() const { return schema_version >= 9; }
  bool has_moves() const { return schema_version >= 10; }
  // Refuses a read-only store; otherwise PrepareWrite. Every writer calls it first.
  void RequireWritable(const char* what);
  // WAL mode and, for an older file, MigrateToCurrent: once, before the first write.
  void PrepareWrite();

  // Open's checks (they throw the first problem, kData): PRAGMA quick_check (or the slower full
  // integrity_check), then the schema objects, the metadata's checksum and shape, the run state's
  // checksum and the set of waves. Verify runs them one by one.
  std::vector<std::string> StorageProblems(bool full);
  // Every table, index, trigger and view is one the schema (of the file's version) creates.
  void CheckSchemaObjects();
  // The metadata's checksum, then its shape: bits, components and positions numbered 0 .. n-1,
  // known kinds, and (v6) experiments numbered 0 .. n-1, at least one, with distinct names, whose
  // counts add up to the outputs, measured points and components.
  void CheckMetadata();
  // CheckMetadata's part for the table experiment (v6), once the other counts are known.
  void CheckExperiments(std::size_t measured);
  void CheckRunState();
  // The wave rows are numbered 0 .. n-1; n is the wave_count the writer recorded (v5); a finished
  // run holds at least the complete waves it recorded (waves_completed); no particle or failure row
  // belongs to a wave without a row. `full` (verify) also finds orphans that are not whole numbers.
  void CheckWaveSet(bool full);

  // The wave row's SELECT (kWaveColumns, or their v1 equivalent) without WHERE / ORDER BY.
  std::string WaveSelect() const;
  // The particle row's SELECT (kParticleColumns, or their v1/v2 equivalent), likewise.
  std::string ParticleSelect() const;
  // One wave read from a row of WaveSelect(): every vector checked against the shape, its
  // particles loaded (all of them, in candidate order) and its checksum verified. Errors are
  // kData naming the wave (from 1) and the field. expected_wave: the 0-based number it must have.
  WaveRecord ReadWave(history::Statement& row, int expected_wave);

  // The first wave that is not complete and its next_index; nullopt when every wave is complete.
  struct PartialWave {
    int wave = 0;
    std::int64_t next_index = 0;
    bool ended = false;
  };
  std::optional<PartialWave> FindPartial();

  // Writers: recompute / extend the wave's checksum and store it, and the run-level ones.
  void StoreWaveHash(int wave);
  void ExtendWaveChain(int wave);
  // Writes failure rows (replacing any of the same candidate).
  void InsertFailures(int wave, std::span<const SimulationFailure> rows);
  void StoreRunHashes();
  // The run state's part only (v5: with the wave count), when a wave row is added.
  void StoreRunStateHash();
  // An older file opened for writing becomes the current version: new columns and tables,
  // checksums of what it holds.
  void MigrateToCurrent();
};

}  // namespace combabc
