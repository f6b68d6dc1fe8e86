#pragma once
// Checksums of a run history (schema v2, private to src/history): 64-bit FNV-1a over a canonical
// serialisation of the rows as SQLite returns them. The algorithm and what each checksum covers
// are documented in docs/history.md, "Checksums"; history_load.cpp verifies them and
// history_store.cpp keeps them current.
#include <cstdint>
#include <optional>
#include <string>

#include "combabc/core/fnv1a.hpp"
#include "history/history_sqlite.hpp"

namespace combabc::history {

class Fnv1a64 {
 public:
  void Add(const void* data, std::size_t size);
  void AddInt(std::int64_t value);
  // One column of the current row: a storage-class tag byte, then the value (8 little-endian
  // bytes for INTEGER and REAL; an 8-byte length and the bytes for TEXT and BLOB; nothing for
  // NULL).
  void AddColumn(const Statement& row, int column);
  void AddColumns(const Statement& row, int first, int count);
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = kFnv1aOffsetBasis;
};

// As stored: 16 lower-case hex digits. nullopt for anything else.
std::string HexDigest(std::uint64_t hash);
std::optional<std::uint64_t> ParseHexDigest(const std::string& text);

// The immutable description of the run: provenance, problem, bits, components, positions, data,
// from schema v3 the reals, the proposal options and the fingerprint, and from v6 the experiments.
// `schema_version` says which tables the file has.
std::uint64_t MetadataHash(Database& db, int schema_version);
// The run row's mutable part: status, end time, termination, message, resume count, summary; then
// the stop limits a resume set, and (schema v5) the number of wave rows the writer recorded.
std::uint64_t RunStateHash(Database& db, int schema_version);

// The particle rows of one wave, fed in candidate order (the state a wave's checksum starts from).
// Schema v3 added `reals`, last, so that a v2 checksum is the same hash over the first six; v7
// the multi-fidelity columns after it (NULL in a single-fidelity run, and then not hashed),
// likewise; v10 the ancestor (NULL for a particle drawn afresh, and then not hashed).
inline constexpr const char* kParticleColumns =
    "candidate, bits, log_weight, weight, distance, output, reals, multiplier, confirmed, "
    "low_distance, ancestor";
inline constexpr int kParticleColumnCountV2 = 6;
inline constexpr int kParticleColumnCountV3 = 7;
inline constexpr int kParticleColumnCount = 10;  // up to v9: the columns before the ancestor
inline constexpr int kParticleAncestorColumn = 10;
// The wave row's columns in checksum order: the first 21, then (v3) reals_mean and reals_sd after
// content_hash, which is not hashed itself, then (v4) the failure count, then (v7) the
// multi-fidelity columns (NULL in a single-fidelity run, and then not hashed), then (v8) the
// pattern classes (NULL in a wave without any, and then not hashed), then (v10) the move
// statistics (NULL in a rejection wave, and then not hashed). Older files select constants in
// their place.
inline constexpr const char* kWaveColumns =
    "wave, thresholds, phi, proposal, started_at, accepted_needed, next_index, accepted_so_far, "
    "total_simulations, ended, complete, candidates, accepted, acceptance_rate, marginals_paper, "
    "marginals_importance, ess, distinct_count, wall_seconds, ended_at, discarded, content_hash, "
    "reals_mean, reals_sd, failures, continue_if_accepted, continue_if_rejected, "
    "expensive_simulations, cheap_seconds, expensive_seconds, unkept_false_positives, "
    "unkept_false_positive_log_w2, next_continue_if_accepted, "
    "next_continue_if_rejected, cost_ratio, pattern_bits, pattern_mass, pattern_proposal, "
    "pattern_flagged, move_survivor_ess, move_step, move_rounds, move_proposed, move_accepted, "
    "move_independent_proposed, move_independent_accepted";
inline constexpr int kWaveHashedColumnCount = 21;
inline constexpr int kWaveRealsColumn = 22;     // reals_mean, then reals_sd (hashed from v3)
inline constexpr int kWaveFailuresColumn = 24;  // hashed from v4
inline constexpr int kWaveFidelityColumn = 25;  // the 10 multi-fidelity columns (hashed from v7)
inline constexpr int kWaveFidelityColumnCount = 10;
inline constexpr int kWavePatternColumn = 35;  // the 4 pattern-class columns (hashed from v8)
inline constexpr int kWavePatternColumnCount = 4;
inline constexpr int kWaveMovesColumn = 39;  // the 7 move columns (hashed from v10)
inline constexpr int kWaveMovesColumnCount = 7;

// The failure rows of one wave, fed in candidate order after its particles (schema v4).
inline constexpr const char* kFailureColumns = "candidate, reason";
inline constexpr int kFailureColumnCount = 2;

// A wave's checksum, built as its particles are read: AddParticle per particle row (in candidate
// order), then Finish with the wave row. The schema version decides which columns are hashed.
class WaveHasher {
 public:
  WaveHasher() = default;  // the current schema: what writers produce
  explicit WaveHasher(int schema_version)
      : v3_(schema_version >= 3),
        v4_(schema_version >= 4),
        v7_(schema_version >= 7),
        v8_(schema_version >= 8),
        v10_(schema_version >= 10) {}
  void AddParticle(const Statement& particle_row);
  // v4: after every particle; failures are hashed apart so that the two can be fed in turn.
  void AddFailure(const Statement& failure_row);
  std::uint64_t Finish(const Statement& wave_row) const;
  std::int64_t particles() const { return count_; }

 private:
  Fnv1a64 hash_;
  Fnv1a64 failure_hash_;
  std::int64_t count_ = 0;
  std::int64_t failures_ = 0;
  bool v3_ = true;
  bool v4_ = true;
  bool v7_ = true;
  bool v8_ = true;
  bool v10_ = true;
};

}  // namespace combabc::history
