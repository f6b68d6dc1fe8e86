#include "history/history_hash.hpp"

#include <sqlite3.h>

#include <cstdio>
#include <cstring>

namespace combabc::history {
namespace {

// Every row of `sql`, then the row count (so that rows cannot shift between tables unnoticed).
void AddRows(Fnv1a64& hash, Database& db, const char* sql, int columns) {
  Statement rows(db, sql);
  std::int64_t count = 0;
  while (rows.Step()) {
    hash.AddColumns(rows, 0, columns);
    ++count;
  }
  hash.AddInt(count);
}

// Columns [first, first + count) of `row` are all NULL: the multi-fidelity columns of a
// single-fidelity run (schema v7), or the move columns of a rejection wave (v10), which its
// checksums skip, so that the checksum of a wave written before stands after the file is upgraded.
bool AllNull(const Statement& row, int first, int count) {
  for (int c = first; c < first + count; ++c) {
    if (!row.IsNull(c)) return false;
  }
  return true;
}

}  // namespace

void Fnv1a64::Add(const void* data, std::size_t size) {
  hash_ = Fnv1a({static_cast<const unsigned char*>(data), size}, hash_);
}

void Fnv1a64::AddInt(std::int64_t value) {
  std::uint8_t bytes[8];
  for (int i = 0; i < 8; ++i) {
    bytes[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(value) >> (8 * i));
  }
  Add(bytes, sizeof bytes);
}

void Fnv1a64::AddColumn(const Statement& row, int column) {
  const int type = row.Type(column);
  const auto tag = static_cast<std::uint8_t>(type);
  Add(&tag, 1);
  switch (type) {
    case SQLITE_INTEGER:
      AddInt(row.Int(column));
      break;
    case SQLITE_FLOAT: {
      const double value = row.Real(column);
      std::int64_t bits = 0;
      std::memcpy(&bits, &value, sizeof bits);
      AddInt(bits);
      break;
    }
    case SQLITE_TEXT:
    case SQLITE_BLOB: {
      const auto bytes = row.Bytes(column);
      AddInt(static_cast<std::int64_t>(bytes.size()));
      Add(bytes.data(), bytes.size());
      break;
    }
    default:  // NULL: the tag says it all
      break;
  }
}

void Fnv1a64::AddColumns(const Statement& row, int first, int count) {
  for (int c = first; c < first + count; ++c) AddColumn(row, c);
}

std::string HexDigest(std::uint64_t hash) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

std::optional<std::uint64_t> ParseHexDigest(const std::string& text) {
  if (text.size() != 16) return std::nullopt;
  std::uint64_t value = 0;
  for (char c : text) {
    int digit = 0;
    if (c >= '0' && c <= '9') {
      digit = c - '0';
    } else if (c >= 'a' && c <= 'f') {
      digit = c - 'a' + 10;
    } else {
      return std::nullopt;
    }
    value = (value << 4) | static_cast<std::uint64_t>(digit);
  }
  return value;
}

std::uint64_t MetadataHash(Database& db, int schema_version) {
  Fnv1a64 hash;
  AddRows(hash,
          db,
          "SELECT config_text, config_path, combabc_version, git_hash, seed, threads, start_time, "
          "estimator, dimension, position_unit FROM run WHERE id = 1",
          10);
  AddRows(hash, db, "SELECT bit, name, prior FROM bit ORDER BY bit", 3);
  AddRows(hash, db, "SELECT component, name, kind, required FROM component ORDER BY component", 4);
  AddRows(hash, db, "SELECT i, position FROM output_position ORDER BY i", 2);
  AddRows(hash, db, "SELECT i, position, value FROM measured ORDER BY i", 3);
  AddRows(hash,
          db,
          "SELECT key, value FROM meta WHERE key IN ('format', 'schema_version') ORDER BY key",
          2);
  if (schema_version >= 3) {
    AddRows(hash, db, "SELECT i, name, kind, low, high, mean, sd FROM real ORDER BY i", 7);
    AddRows(hash,
            db,
            "SELECT binary_kernel, min_correlation, max_predecessors, ridge, min_marginal, clip, "
            "continuous_kernel, scale, tempering_form FROM proposal WHERE id = 1",
            9);
    AddRows(hash,
            db,
            "SELECT key, value FROM meta WHERE substr(key, 1, 12) = 'fingerprint_' ORDER BY key",
            2);
  }
  // v6: the experiments, after everything an older file hashes, so that its digest is unchanged.
  if (schema_version >= 6) {
    AddRows(hash,
            db,
            "SELECT e, name, description, outputs, measured, components FROM experiment ORDER BY e",
            6);
  }
  return hash.value();
}

std::uint64_t RunStateHash(Database& db, int schema_version) {
  Fnv1a64 hash;
  AddRows(hash,
          db,
          "SELECT status, end_time, termination, message, resume_count, waves_completed, "
          "simulations, simulations_discarded, wall_seconds FROM run WHERE id = 1",
          9);
  // The stop limits a resume raised (meta rows stop_limit_<key>): hashed only when there are any,
  // so that the digest of a run never resumed with raised limits is what it always was.
  if (db.QueryInt("SELECT count(*) FROM meta WHERE substr(key, 1, 11) = 'stop_limit_'") > 0) {
    AddRows(hash,
            db,
            "SELECT key, value FROM meta WHERE substr(key, 1, 11) = 'stop_limit_' ORDER BY key",
            2);
  }
  // v5: the wave rows the writer recorded (meta row wave_count), so that waves deleted by hand are
  // told from waves never written.
  if (schema_version >= 5) {
    AddRows(hash, db, "SELECT key, value FROM meta WHERE key = 'wave_count'", 2);
  }
  return hash.value();
}

void WaveHasher::AddParticle(const Statement& particle_row) {
  const int columns = v3_ ? kParticleColumnCountV3 : kParticleColumnCountV2;
  hash_.AddColumns(particle_row, 0, columns);
  if (v7_ && !AllNull(particle_row, columns, kParticleColumnCount - columns)) {
    hash_.AddColumns(particle_row, columns, kParticleColumnCount - columns);
  }
  if (v10_ && !particle_row.IsNull(kParticleAncestorColumn)) {
    hash_.AddColumn(particle_row, kParticleAncestorColumn);
  }
  ++count_;
}

void WaveHasher::AddFailure(const Statement& failure_row) {
  failure_hash_.AddColumns(failure_row, 0, kFailureColumnCount);
  ++failures_;
}

std::uint64_t WaveHasher::Finish(const Statement& wave_row) const {
  Fnv1a64 hash = hash_;
  hash.AddInt(count_);
  hash.AddColumns(wave_row, 0, kWaveHashedColumnCount);
  if (v3_) hash.AddColumns(wave_row, kWaveRealsColumn, 2);
  if (v4_) {
    hash.AddColumn(wave_row, kWaveFailuresColumn);
    hash.AddInt(static_cast<std::int64_t>(failure_hash_.value()));
    hash.AddInt(failures_);
  }
  if (v7_ && !AllNull(wave_row, kWaveFidelityColumn, kWaveFidelityColumnCount)) {
    hash.AddColumns(wave_row, kWaveFidelityColumn, kWaveFidelityColumnCount);
  }
  if (v8_ && !AllNull(wave_row, kWavePatternColumn, kWavePatternColumnCount)) {
    hash.AddColumns(wave_row, kWavePatternColumn, kWavePatternColumnCount);
  }
  if (v10_ && !AllNull(wave_row, kWaveMovesColumn, kWaveMovesColumnCount)) {
    hash.AddColumns(wave_row, kWaveMovesColumn, kWaveMovesColumnCount);
  }
  return hash.value();
}

}  // namespace combabc::history
