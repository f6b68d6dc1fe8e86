// HistoryStore against damaged files: wrong-length and NULL columns, single-bit flips, schema v1
// files, and a second writer. Every damage must give a one-line error (or be provably harmless),
// never a crash or a silently different history.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>

#include "combabc/core/error.hpp"
#include "combabc/export/export.hpp"
#include "combabc/history/history_store.hpp"
#include "history/fake_run.hpp"
#include "history/history_hash.hpp"
#include "history/history_sqlite.hpp"
#include "history/sql_test_support.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;
using testing::FakeRunOptions;
using testing::MakeFakeHistory;
using testing::MakeFakeMetadata;
using testing::RecordWave;
using testing::Sql;
using testing::TempFolder;

FakeRunOptions SmallRun() {
  FakeRunOptions options;
  options.waves = 3;
  options.per_wave = 12;
  options.dimension = 10;
  options.points = 8;
  options.reals = 2;
  return options;
}

class HistoryIntegrityTest : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return dir_ / name; }

  // A finished run (one self-contained file), or one killed in wave 2 (0-based 1).
  std::string WriteFinished(const std::string& name) {
    std::string path = Path(name);
    const RunHistory history = MakeFakeHistory(SmallRun());
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    for (const WaveRecord& wave : history.waves) RecordWave(store, wave, 5);
    store.Finish(history.summary);
    return path;
  }
  std::string WriteKilled(const std::string& name) {
    std::string path = Path(name);
    const RunHistory history = MakeFakeHistory(SmallRun());
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], 5);
    RecordWave(store, history.waves[1], 5, /*stop_after_batches=*/3);
    return path;
  }

  const TempFolder dir_{"integrity-test"};
};

// Stores the run's checksums as combabc computed them for `version`.
void RehashMetadataAndRunState(history::Database& db, int version) {
  history::Statement meta(db, "UPDATE meta SET value = ?2 WHERE key = ?1");
  meta.Bind(1, std::string("metadata_hash"))
      .Bind(2, history::HexDigest(history::MetadataHash(db, version)))
      .Run();
  meta.Bind(1, std::string("run_state_hash"))
      .Bind(2, history::HexDigest(history::RunStateHash(db, version)))
      .Run();
}

// What a v9 file (before resample-move waves) looks like, made from a v10 one: no move columns
// and no ancestors, and its checksums as combabc computed them for v9. Made from a rejection run:
// a wave's checksum skips move columns that are all NULL and NULL ancestors, so the waves' stand.
void DowngradeToV9(const std::string& path) {
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  for (const char* column : {"move_survivor_ess",
                             "move_step",
                             "move_rounds",
                             "move_proposed",
                             "move_accepted",
                             "move_independent_proposed",
                             "move_independent_accepted"}) {
    db.Exec((std::string("ALTER TABLE wave DROP COLUMN ") + column).c_str());
  }
  db.Exec(R"sql(
    ALTER TABLE particle DROP COLUMN ancestor;
    UPDATE meta SET value = '9' WHERE key = 'schema_version';
    PRAGMA user_version = 9;)sql");
  RehashMetadataAndRunState(db, 9);
  transaction.Commit();
}

// What a v7 file (before pattern classes) looks like, made from a v8 one: no pattern-class
// columns, and its checksums as combabc computed them for v7. Made from a run without pattern
// classes: a wave's checksum skips pattern columns that are all NULL, so the waves' stand.
void DowngradeToV7(const std::string& path) {
  DowngradeToV9(path);
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  for (const char* column :
       {"pattern_bits", "pattern_mass", "pattern_proposal", "pattern_flagged"}) {
    db.Exec((std::string("ALTER TABLE wave DROP COLUMN ") + column).c_str());
  }
  db.Exec(R"sql(
    UPDATE meta SET value = '7' WHERE key = 'schema_version';
    PRAGMA user_version = 7;)sql");
  RehashMetadataAndRunState(db, 7);
  transaction.Commit();
}

// What a v6 file (before multi-fidelity runs) looks like, made from a v7 one of a single-fidelity
// run: no multi-fidelity columns (all NULL there), and its checksums as combabc computed them for
// v6.
void DowngradeToV6(const std::string& path) {
  DowngradeToV7(path);
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  for (const char* column : {"continue_if_accepted",
                             "continue_if_rejected",
                             "expensive_simulations",
                             "cheap_seconds",
                             "expensive_seconds",
                             "unkept_false_positives",
                             "unkept_false_positive_log_w2",
                             "next_continue_if_accepted",
                             "next_continue_if_rejected",
                             "cost_ratio"}) {
    db.Exec((std::string("ALTER TABLE wave DROP COLUMN ") + column).c_str());
  }
  db.Exec(R"sql(
    ALTER TABLE particle DROP COLUMN multiplier;
    ALTER TABLE particle DROP COLUMN confirmed;
    ALTER TABLE particle DROP COLUMN low_distance;
    UPDATE meta SET value = '6' WHERE key = 'schema_version';
    PRAGMA user_version = 6;)sql");
  RehashMetadataAndRunState(db, 6);
  transaction.Commit();
}

// What a v5 file (before the experiments were recorded) looks like, made from a v6 one: no table
// experiment, and its checksums as combabc computed them for v5.
void DowngradeToV5(const std::string& path) {
  DowngradeToV6(path);
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  db.Exec(R"sql(
    DROP TABLE experiment;
    UPDATE meta SET value = '5' WHERE key = 'schema_version';
    PRAGMA user_version = 5;)sql");
  RehashMetadataAndRunState(db, 5);
  transaction.Commit();
}

// What a v4 file (before the wave count was recorded) looks like, made from a v6 one: no meta row
// wave_count, and its checksums as combabc computed them for v4.
void DowngradeToV4(const std::string& path) {
  DowngradeToV5(path);
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  db.Exec(R"sql(
    DELETE FROM meta WHERE key = 'wave_count';
    UPDATE meta SET value = '4' WHERE key = 'schema_version';
    PRAGMA user_version = 4;)sql");
  RehashMetadataAndRunState(db, 4);
  transaction.Commit();
}

// The v3 additions dropped: what a v2 run (without reals) holds, still with v3 checksums.
void DropV3(const std::string& path) {
  DowngradeToV4(path);
  Sql(path, R"sql(
    ALTER TABLE wave DROP COLUMN failures;
    DROP TABLE failure;
    ALTER TABLE wave DROP COLUMN reals_mean;
    ALTER TABLE wave DROP COLUMN reals_sd;
    ALTER TABLE particle DROP COLUMN reals;
    DROP TABLE real;
    DROP TABLE proposal;
    DELETE FROM meta WHERE substr(key, 1, 12) = 'fingerprint_';)sql");
}

// What a v2 file looks like, made from a v3 one: its tables, and its checksums computed as
// combabc 0.1 computed them (history_hash.cpp keeps the v2 forms for reading such files).
void DowngradeToV2(const std::string& path) {
  DropV3(path);
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  db.Exec("UPDATE meta SET value = '2' WHERE key = 'schema_version'; PRAGMA user_version = 2");
  std::vector<std::pair<std::int64_t, std::string>> digests;
  std::string columns = history::kWaveColumns;
  columns.erase(columns.find(", reals_mean"));
  history::Statement waves(db, ("SELECT " + columns + " FROM wave ORDER BY wave").c_str());
  while (waves.Step()) {
    history::WaveHasher hasher(2);
    history::Statement particles(db,
                                 "SELECT candidate, bits, log_weight, weight, distance, output "
                                 "FROM particle WHERE wave = ?1 ORDER BY candidate");
    particles.Bind(1, waves.Int(0));
    while (particles.Step()) hasher.AddParticle(particles);
    digests.emplace_back(waves.Int(0), history::HexDigest(hasher.Finish(waves)));
  }
  history::Statement store(db, "UPDATE wave SET content_hash = ?2 WHERE wave = ?1");
  for (const auto& [wave, digest] : digests) store.Bind(1, wave).Bind(2, digest).Run();
  history::Statement meta(db, "UPDATE meta SET value = ?1 WHERE key = 'metadata_hash'");
  meta.Bind(1, history::HexDigest(history::MetadataHash(db, 2))).Run();
  transaction.Commit();
}

// What a v3 file (before failed simulations were recorded) looks like, made from a v4 one without
// failures: its tables, and its checksums as combabc computed them for v3.
void DowngradeToV3(const std::string& path) {
  DowngradeToV4(path);
  Sql(path, R"sql(
    ALTER TABLE wave DROP COLUMN failures;
    DROP TABLE failure;)sql");
  history::Database db(path, /*create=*/false, /*read_only=*/false);
  history::Transaction transaction(db);
  db.Exec("UPDATE meta SET value = '3' WHERE key = 'schema_version'; PRAGMA user_version = 3");
  std::vector<std::pair<std::int64_t, std::string>> digests;
  std::string columns = history::kWaveColumns;
  columns.erase(columns.find(", failures"));
  history::Statement waves(db, ("SELECT " + columns + " FROM wave ORDER BY wave").c_str());
  while (waves.Step()) {
    history::WaveHasher hasher(3);
    std::string particle_columns = history::kParticleColumns;
    particle_columns.erase(particle_columns.find(", multiplier"));  // v7 and v10
    history::Statement particles(
        db,
        ("SELECT " + particle_columns + " FROM particle WHERE wave = ?1 ORDER BY candidate")
            .c_str());
    particles.Bind(1, waves.Int(0));
    while (particles.Step()) hasher.AddParticle(particles);
    digests.emplace_back(waves.Int(0), history::HexDigest(hasher.Finish(waves)));
  }
  history::Statement store(db, "UPDATE wave SET content_hash = ?2 WHERE wave = ?1");
  for (const auto& [wave, digest] : digests) store.Bind(1, wave).Bind(2, digest).Run();
  history::Statement meta(db, "UPDATE meta SET value = ?1 WHERE key = 'metadata_hash'");
  meta.Bind(1, history::HexDigest(history::MetadataHash(db, 3))).Run();
  transaction.Commit();
}

// What a v1 file (no checksums, no overshoot column) looks like, made from a v3 one.
void DowngradeToV1(const std::string& path) {
  DropV3(path);
  Sql(path, R"sql(
    ALTER TABLE wave DROP COLUMN content_hash;
    ALTER TABLE wave DROP COLUMN discarded;
    DELETE FROM meta WHERE key IN ('metadata_hash', 'run_state_hash');
    UPDATE meta SET value = '1' WHERE key = 'schema_version';
    PRAGMA user_version = 1;)sql");
}

template <typename F>
Error Catch(F&& f) {
  try {
    f();
  } catch (const Error& error) {
    return error;
  }
  ADD_FAILURE() << "no combabc::Error thrown";
  return Error(ErrorKind::kSoftware, "none");
}

// A clean data error: kind kData (exit 65), one line, naming the file and what it says.
void ExpectDataError(const Error& error, const std::string& path, const std::string& mentions) {
  const std::string what = error.what();
  EXPECT_EQ(error.kind(), ErrorKind::kData) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  EXPECT_EQ(what.rfind(path, 0), 0u) << what;
  EXPECT_NE(what.find(mentions), std::string::npos) << "expected '" << mentions << "' in: " << what;
}

struct Corruption {
  std::string column;  // table.column
  std::string where;
  std::string field;  // as the error names it
  const char* mode;   // NULL, short, long
};

std::string Damage(const Corruption& c) {
  const std::string table = c.column.substr(0, c.column.find('.'));
  const std::string column = c.column.substr(c.column.find('.') + 1);
  // Bits are bytes; everything else is doubles, 8 bytes each.
  const std::string unit = column == "bits" ? "1" : "8";
  // bits is NOT NULL in the schema: the empty BLOB is as missing as NULL can be there.
  std::string value = column == "bits" ? "x''" : "NULL";
  if (std::string(c.mode) == "short") {
    value = "substr(" + column + ", 1, length(" + column + ") - " + unit + ")";
  }
  if (std::string(c.mode) == "long") value = column + " || zeroblob(" + unit + ")";
  return "UPDATE " + table + " SET " + column + " = " + value + " WHERE " + c.where;
}

// Each vector column the engine or the exporter indexes, in a complete wave and in the partial
// wave of a killed run, made NULL, one element short and one element long.
std::vector<Corruption> Corruptions(bool killed, bool reals) {
  const std::string particle =
      "wave = 1 AND candidate = (SELECT min(candidate) FROM particle WHERE wave = 1)";
  const std::string first =
      "wave = 0 AND candidate = (SELECT min(candidate) FROM particle WHERE wave = 0)";
  std::vector<Corruption> out;
  for (const char* mode : {"NULL", "short", "long"}) {
    out.push_back({"wave.thresholds", "wave = 0", "wave 1, thresholds", mode});
    out.push_back({"wave.proposal", "wave = 1", "wave 2, proposal", mode});
    out.push_back({"wave.marginals_paper", "wave = 0", "wave 1, marginals_paper", mode});
    out.push_back({"wave.marginals_importance", "wave = 0", "wave 1, marginals_importance", mode});
    out.push_back({"particle.bits", first, "bits", mode});
    out.push_back({"particle.distance", first, "distance", mode});
    out.push_back({"particle.distance", particle, "wave 2, particle", mode});
    out.push_back({"wave.thresholds", "wave = 1", "wave 2, thresholds", mode});
    // NULL is a valid output (not kept); a wrong length is not.
    if (std::string(mode) != "NULL") out.push_back({"particle.output", particle, "output", mode});
    if (reals) {
      out.push_back({"particle.reals", first, "wave 1, particle", mode});
      out.push_back({"particle.reals", particle, "reals", mode});
      out.push_back({"wave.reals_mean", "wave = 0", "wave 1, reals_mean", mode});
      out.push_back({"wave.reals_sd", "wave = 0", "wave 1, reals_sd", mode});
    }
  }
  if (!killed) {
    for (const char* mode : {"NULL", "short", "long"}) {
      out.push_back({"wave.marginals_paper", "wave = 2", "wave 3, marginals_paper", mode});
    }
  }
  return out;
}

// Resume, report-side loading and export of every damaged copy stop with a clean kData error;
// verify lists the problem. Schema v1 files (no checksums) rely on the length checks alone.
TEST_F(HistoryIntegrityTest, WrongLengthOrNullColumnsAreDataErrorsNamingWaveAndField) {
  for (const bool v1 : {false, true}) {
    for (const bool killed : {false, true}) {
      const std::string original = killed ? WriteKilled("killed.db") : WriteFinished("finished.db");
      if (v1) DowngradeToV1(original);
      for (const Corruption& c : Corruptions(killed, /*reals=*/!v1)) {
        SCOPED_TRACE(c.column + " " + c.mode + " where " + c.where + (v1 ? " (v1)" : "") +
                     (killed ? " (killed run)" : ""));
        const std::string path = Path("damaged.db");
        for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix);
        fs::copy_file(original, path);
        if (fs::exists(original + "-wal")) fs::copy_file(original + "-wal", path + "-wal");
        Sql(path, Damage(c));

        ExpectDataError(
            Catch([&] { HistoryStore::Open(path, true).LoadHistory(); }), path, c.field);
        ExpectDataError(
            Catch([&] { HistoryStore::Open(path, true).LoadResumePoint(); }), path, c.field);
        const std::string out = Path("export");
        ExpectDataError(Catch([&] { ExportRun(path, out); }), path, c.field);
        EXPECT_FALSE(fs::exists(out)) << "no partial export";
        const HistoryCheck check = HistoryStore::Verify(path);
        ASSERT_FALSE(check.problems.empty());
        EXPECT_NE(check.problems.front().find(c.field), std::string::npos)
            << check.problems.front();
        if (killed && !v1) {
          // The resume refuses before it rewrites anything.
          ExpectDataError(Catch([&] { HistoryStore::Open(path).BeginResume(); }), path, c.field);
          EXPECT_EQ(HistoryStore::Open(path, true).LoadMetadata().resume_count, 0);
        }
      }
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(original + suffix);
    }
  }
}

// Found by the history_patch fuzzer: a count stored as a REAL (9.3e18, Inf) reads as INT64_MAX and
// summing the waves' counts overflowed (undefined behaviour). Without checksums (schema v1) only
// the value checks stand between such a file and the sums.
TEST_F(HistoryIntegrityTest, HugeOrNonIntegerCountsAreDataErrors) {
  const std::string original = WriteFinished("finished.db");
  DowngradeToV1(original);
  for (const char* value : {"9.3e18", "9e999", "-9e999", "2.5", "1099511627777"}) {
    for (const char* column : {"candidates", "accepted", "next_index"}) {
      SCOPED_TRACE(std::string(column) + " = " + value);
      const std::string path = Path("damaged.db");
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix);
      fs::copy_file(original, path);
      Sql(path, std::string("UPDATE wave SET ") + column + " = " + value + " WHERE wave = 1");
      ExpectDataError(Catch([&] { HistoryStore::Open(path, true).LoadHistory(); }), path, column);
    }
  }
}

std::string Describe(const RunMetadata& m) {
  std::ostringstream out;
  out << m.config_text << '|' << m.config_path << '|' << m.combabc_version << '|' << m.git_hash
      << '|' << m.seed << '|' << m.threads << '|' << m.start_time << '|' << m.end_time << '|'
      << ToString(m.status) << '|' << m.termination << '|' << m.summary_message << '|'
      << m.resume_count << '|' << m.estimator << '|' << m.dimension << '|' << m.position_unit << '|'
      << m.schema_version;
  for (const auto& name : m.bit_names) out << '|' << name;
  for (double p : m.bit_prior_one) out << '|' << p;
  for (const auto& c : m.distance_components) {
    out << '|' << c.name << ToString(c.kind) << c.required;
  }
  for (double x : m.output_positions) out << '|' << x;
  for (std::size_t i = 0; i < m.measured.positions.size(); ++i) {
    out << '|' << m.measured.positions[i] << ',' << m.measured.values[i];
  }
  for (const StoredExperiment& x : m.experiments) {
    out << '|' << x.name << ',' << x.description << ',' << x.outputs << ',' << x.measured << ','
        << x.components;
  }
  return out.str();
}

bool SameLoad(const RunHistory& a, const RunHistory& b, std::string* where) {
  if (!SameHistory(a, b, where)) return false;
  for (std::size_t t = 0; t < a.waves.size(); ++t) {
    const double x = a.waves[t].wall_seconds, y = b.waves[t].wall_seconds;
    if (!(x == y || (std::isnan(x) && std::isnan(y))) ||
        a.waves[t].acceptance_rate != b.waves[t].acceptance_rate ||
        a.waves[t].discarded != b.waves[t].discarded) {
      *where = "wave " + std::to_string(t) + " statistics";
      return false;
    }
  }
  const RunSummary &s = a.summary, &r = b.summary;
  if (s.termination != r.termination || s.message != r.message ||
      s.waves_completed != r.waves_completed || s.simulations != r.simulations ||
      s.simulations_discarded != r.simulations_discarded || s.wall_seconds != r.wall_seconds) {
    *where = "summary";
    return false;
  }
  return true;
}

// Single-bit flips across the whole file, at a fixed list of positions: each is detected (an
// error on open / load, or a problem from verify) or provably harmless (the loaded history and
// metadata are exactly the original's). None may go unnoticed and change what is read.
TEST_F(HistoryIntegrityTest, EverySingleBitFlipIsDetectedOrHarmless) {
  const std::string original = WriteFinished("finished.db");
  std::ifstream in(original, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 4096u);
  const RunHistory expected = HistoryStore::Open(original, true).LoadHistory();
  const std::string expected_metadata = Describe(HistoryStore::Open(original, true).LoadMetadata());

  const std::string path = Path("flipped.db");
  int flips = 0, detected = 0, harmless = 0;
  for (std::size_t position = 3; position < bytes.size();
       position += testing::Stride(41), ++flips) {
    std::vector<char> damaged = bytes;
    damaged[position] = static_cast<char>(damaged[position] ^ (1 << (flips % 8)));
    fs::remove(path);
    std::ofstream(path, std::ios::binary)
        .write(damaged.data(), static_cast<std::streamsize>(damaged.size()));
    bool caught = false;
    RunHistory loaded;
    std::string metadata;
    try {
      const HistoryStore store = HistoryStore::Open(path, true);
      loaded = store.LoadHistory();
      metadata = Describe(store.LoadMetadata());
    } catch (const Error& error) {
      caught = true;
      EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos) << error.what();
    }
    bool reported = caught;
    try {
      reported = reported || !HistoryStore::Verify(path).problems.empty();
    } catch (const Error&) {
      reported = true;
    }
    std::string where;
    if (!caught && SameLoad(expected, loaded, &where) && metadata == expected_metadata) {
      ++harmless;
      continue;
    }
    EXPECT_TRUE(caught) << "flip of bit " << flips % 8 << " at byte " << position
                        << " was read silently: " << where;
    EXPECT_TRUE(reported) << "verify missed the flip at byte " << position;
    detected += caught;
  }
  // Most of this small file is free space; the flips that land in live rows are all detected.
  EXPECT_GT(detected, testing::kSanitized ? 25 : 100);
  std::cout << flips << " flips: " << detected << " detected, " << harmless << " harmless\n";
}

TEST_F(HistoryIntegrityTest, VerifyAcceptsSoundFilesAndSaysWhenThereAreNoChecksums) {
  const std::string finished = WriteFinished("finished.db");
  HistoryCheck check = HistoryStore::Verify(finished);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_TRUE(check.checksummed);
  EXPECT_EQ(check.waves, 3);
  const std::string killed = WriteKilled("killed.db");
  check = HistoryStore::Verify(killed);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();

  DowngradeToV1(finished);
  const RunHistory v1 = HistoryStore::Open(finished, true).LoadHistory();
  EXPECT_EQ(v1.waves.size(), 3u) << "a v1 file still reads";
  check = HistoryStore::Verify(finished);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_FALSE(check.checksummed);
  EXPECT_EQ(check.schema_version, 1);
}

TEST_F(HistoryIntegrityTest, AV1RunResumedIsUpgradedToTheCurrentChecksummedSchema) {
  const std::string path = WriteKilled("killed.db");
  DowngradeToV1(path);
  const ResumePoint v1 = HistoryStore::Open(path, true).LoadResumePoint();
  {
    HistoryStore store = HistoryStore::Open(path);
    const ResumePoint point = store.BeginResume();
    EXPECT_EQ(point.partial_next_index, v1.partial_next_index);
    EXPECT_EQ(point.partial_accepted.size(), v1.partial_accepted.size());
  }
  const HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.checksummed);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  // And the upgraded checksums protect it: a changed weight is caught.
  Sql(path,
      "UPDATE particle SET weight = 0.5 WHERE wave = 0 AND candidate = (SELECT min(candidate) FROM "
      "particle WHERE wave = 0)");
  ExpectDataError(
      Catch([&] { HistoryStore::Open(path, true).LoadHistory(); }), path, "wave 1, content_hash");
}

TEST_F(HistoryIntegrityTest, MetadataAndRunStateAreChecksummed) {
  const std::string path = WriteFinished("finished.db");
  Sql(path, "UPDATE measured SET value = value + 1e-9 WHERE i = 0");
  ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, "meta.metadata_hash");
  const std::string other = WriteFinished("other.db");
  Sql(other, "UPDATE run SET simulations = simulations + 1");
  ExpectDataError(Catch([&] { HistoryStore::Open(other, true); }), other, "meta.run_state_hash");
  EXPECT_FALSE(HistoryStore::Verify(other).problems.empty());
}

// Two processes: the one writing the run holds it; a second writer is refused with the first's
// pid, readers are not, and the lock goes when the holder dies (even by SIGKILL).
TEST_F(HistoryIntegrityTest, ASecondWriterIsRefusedWhileTheFirstHoldsTheRun) {
  const std::string path = WriteKilled("killed.db");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t holder = ::fork();
  ASSERT_NE(holder, -1);
  if (holder == 0) {
    ::close(ready[0]);
    HistoryStore store = HistoryStore::Open(path);
    store.BeginResume();
    const char byte = 1;
    (void)!::write(ready[1], &byte, 1);
    ::pause();  // until killed
    ::_exit(0);
  }
  ::close(ready[1]);
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ::close(ready[0]);

  Error error = Catch([&] { HistoryStore::Open(path); });
  EXPECT_EQ(error.kind(), ErrorKind::kCantCreate);
  EXPECT_NE(std::string(error.what()).find("another process (pid " + std::to_string(holder) + ")"),
            std::string::npos)
      << error.what();
  EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos);
  error =
      Catch([&] { HistoryStore::Create(path, MakeFakeMetadata(SmallRun()), /*overwrite=*/true); });
  EXPECT_EQ(error.kind(), ErrorKind::kCantCreate);
  EXPECT_NE(std::string(error.what()).find("another process"), std::string::npos) << error.what();
  EXPECT_EQ(HistoryStore::Open(path, true).LoadMetadata().resume_count, 1) << "readers may read";

  ::kill(holder, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(holder, &status, 0), holder);
  HistoryStore store = HistoryStore::Open(path);
  EXPECT_EQ(store.BeginResume().partial_wave, 1);
}

// A run with continuous parameters whose fingerprint, proposal options and reals' priors are part
// of the metadata checksum: any change to them is a clean data error on open, and verify says so.
TEST_F(HistoryIntegrityTest, RealsProposalAndFingerprintAreCoveredByTheMetadataChecksum) {
  for (const char* damage :
       {"UPDATE real SET low = 2e4 WHERE i = 1",
        "UPDATE real SET name = 'damping' WHERE i = 0",
        "UPDATE proposal SET scale = 1.5",
        "UPDATE proposal SET binary_kernel = 'logistic'",
        "UPDATE proposal SET tempering_form = 'mixture'",
        "UPDATE meta SET value = '0000000000000000' WHERE key = 'fingerprint_data'",
        "DELETE FROM meta WHERE key = 'fingerprint_space'"}) {
    SCOPED_TRACE(damage);
    const std::string path = Path("fingerprinted.db");
    fs::remove(path);
    RunMetadata metadata = MakeFakeMetadata(SmallRun());
    metadata.fingerprint = {{"data", "0123456789abcdef"}, {"space", "fedcba9876543210"}};
    {
      HistoryStore store = HistoryStore::Create(path, metadata);
      const RunHistory history = MakeFakeHistory(SmallRun());
      RecordWave(store, history.waves[0], 5);
    }
    Sql(path, damage);
    ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, "meta.metadata_hash");
    const HistoryCheck check = HistoryStore::Verify(path);
    ASSERT_FALSE(check.problems.empty());
    EXPECT_NE(check.problems.front().find("metadata_hash"), std::string::npos);
  }
}

// A run of two experiments (schema v6), killed in its second wave: 8 output positions, 4 + 4,
// the measured points split after the first, one distance component each.
std::string WriteTwoExperiments(const std::string& path) {
  RunMetadata metadata = MakeFakeMetadata(SmallRun());
  const int measured = static_cast<int>(metadata.measured.positions.size());
  metadata.experiments = {{"near", "load at 0.45 m", 4, 1, 1}, {"far", "", 4, measured - 1, 1}};
  HistoryStore store = HistoryStore::Create(path, metadata);
  const RunHistory history = MakeFakeHistory(SmallRun());
  RecordWave(store, history.waves[0], 5);
  RecordWave(store, history.waves[1], 5, /*stop_after_batches=*/1);
  return path;
}

// The experiments are part of the problem's description: any change to their rows is a clean data
// error on open (the metadata checksum), and verify says so.
TEST_F(HistoryIntegrityTest, ExperimentsAreCoveredByTheMetadataChecksum) {
  for (
      const char* damage :
      {"UPDATE experiment SET name = 'forged' WHERE e = 0",
       "UPDATE experiment SET description = 'load at 0.30 m' WHERE e = 1",
       // Counts moved between experiments still add up: only the checksum tells. (Two
       // statements in one literal, split over two lines on purpose.)
       "UPDATE experiment SET outputs = outputs + 1 WHERE e = 0; "  // NOLINT(bugprone-suspicious-missing-comma)
       "UPDATE experiment SET outputs = outputs - 1 WHERE e = 1",
       "UPDATE experiment SET measured = measured + 0.5 WHERE e = 1",  // a count made REAL
       "DELETE FROM experiment WHERE e = 1",
       "INSERT INTO experiment VALUES (2, 'extra', '', 0, 0, 0)"}) {
    SCOPED_TRACE(damage);
    const std::string path = Path("experiments.db");
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix);
    WriteTwoExperiments(path);
    Sql(path, damage);
    ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, "meta.metadata_hash");
    ExpectDataError(Catch([&] { HistoryStore::Open(path); }), path, "meta.metadata_hash");
    const HistoryCheck check = HistoryStore::Verify(path);
    ASSERT_FALSE(check.problems.empty());
    EXPECT_NE(check.problems.front().find("metadata_hash"), std::string::npos)
        << check.problems.front();
  }
}

// Without the checksum's help (rows changed and the checksum recomputed, as a writer with a bug
// would leave them), the experiments' shape is still checked: rows numbered 0 .. n-1, at least
// one, distinct names, counts that add up to the run's outputs, measured points and components.
TEST_F(HistoryIntegrityTest, ExperimentsThatDoNotAddUpAreDataErrorsEvenUnderAValidChecksum) {
  struct Case {
    const char* sql;
    const char* mentions;
  };
  for (const Case& c : {
           Case{"UPDATE experiment SET outputs = 5 WHERE e = 1",
                "the experiments hold 9 output positions, the run has 8"},
           Case{"UPDATE experiment SET components = 0 WHERE e = 0",
                "the experiments hold 1 distance components, the run has 2"},
           Case{"UPDATE experiment SET measured = measured + 1 WHERE e = 0", "measured points"},
           Case{"UPDATE experiment SET outputs = -1 WHERE e = 0", "experiment 1, outputs"},
           Case{"UPDATE experiment SET outputs = 4.5 WHERE e = 0", "experiment 1, outputs"},
           Case{"UPDATE experiment SET name = 'near' WHERE e = 1", "experiment 2, name"},
           Case{"UPDATE experiment SET e = 5 WHERE e = 1", "rows are not numbered"},
           Case{"DELETE FROM experiment", "the table is empty"},
       }) {
    SCOPED_TRACE(c.sql);
    const std::string path = Path("experiments.db");
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix);
    WriteTwoExperiments(path);
    {
      history::Database db(path, /*create=*/false, /*read_only=*/false);
      history::Transaction transaction(db);
      db.Exec(c.sql);
      RehashMetadataAndRunState(db, kHistorySchemaVersion);
      transaction.Commit();
    }
    ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, c.mentions);
    const HistoryCheck check = HistoryStore::Verify(path);
    ASSERT_FALSE(check.problems.empty());
    EXPECT_NE(check.problems.front().find(c.mentions), std::string::npos) << check.problems.front();
  }
}

// A v5 file (before experiments) reads as one unnamed experiment holding everything; resuming it
// upgrades it to v6 with that experiment's row, under the metadata checksum from then on.
TEST_F(HistoryIntegrityTest, AV5RunReadsAsOneExperimentAndIsUpgradedToV6OnResume) {
  const std::string path = WriteKilled("killed.db");
  const RunMetadata written = MakeFakeMetadata(SmallRun());
  DowngradeToV5(path);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 5);
  const auto expect_one_experiment = [&](const RunMetadata& m) {
    ASSERT_EQ(m.experiments.size(), 1u);
    EXPECT_EQ(m.experiments[0].name, "");
    EXPECT_EQ(m.experiments[0].description, "");
    EXPECT_EQ(m.experiments[0].outputs, static_cast<int>(written.output_positions.size()));
    EXPECT_EQ(m.experiments[0].measured, static_cast<int>(written.measured.positions.size()));
    EXPECT_EQ(m.experiments[0].components, static_cast<int>(written.distance_components.size()));
  };
  RunMetadata metadata = HistoryStore::Open(path, true).LoadMetadata();
  EXPECT_EQ(metadata.schema_version, 5);
  expect_one_experiment(metadata);
  const ResumePoint v5 = HistoryStore::Open(path, true).LoadResumePoint();
  ASSERT_TRUE(v5.has_partial);
  {
    HistoryStore store = HistoryStore::Open(path);
    // Opened for writing, nothing changes before the first write (a refused resume leaves it).
    EXPECT_EQ(HistoryStore::Verify(path).schema_version, 5);
    const ResumePoint point = store.BeginResume();
    EXPECT_EQ(point.partial_next_index, v5.partial_next_index);
    EXPECT_EQ(point.partial_accepted.size(), v5.partial_accepted.size());
  }
  check = HistoryStore::Verify(path);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  metadata = HistoryStore::Open(path, true).LoadMetadata();
  EXPECT_EQ(metadata.schema_version, kHistorySchemaVersion);
  EXPECT_EQ(metadata.resume_count, 1);
  expect_one_experiment(metadata);
  Sql(path, "UPDATE experiment SET name = 'forged'");
  ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, "meta.metadata_hash");
}

TEST_F(HistoryIntegrityTest, ANonFiniteRealIsADataErrorNamingTheParticle) {
  for (const char* value : {"X'000000000000F87F0000000000000040'",     // NaN, 2
                            "X'0000000000000040000000000000F07F'"}) {  // 2, +inf
    SCOPED_TRACE(value);
    const std::string path = WriteFinished("finished.db");
    Sql(path,
        std::string("UPDATE particle SET reals = ") + value +
            " WHERE wave = 1 AND candidate = (SELECT min(candidate) FROM particle WHERE wave = 1)");
    const Error error = Catch([&] { HistoryStore::Open(path, true).LoadHistory(); });
    ExpectDataError(error, path, "wave 2, particle");
    EXPECT_NE(std::string(error.what()).find("reals: corrupt run history: value"),
              std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("is not finite"), std::string::npos) << error.what();
    fs::remove(path);
  }
}

// A v6 file (before multi-fidelity runs) reads as a single-fidelity run; resuming it upgrades it
// to v7 without touching its waves' checksums (NULL multi-fidelity columns are not hashed).
TEST_F(HistoryIntegrityTest, AV6RunReadsAsSingleFidelityAndIsUpgradedToV7OnResume) {
  const std::string path = WriteKilled("killed.db");
  const RunHistory before = HistoryStore::Open(path, true).LoadHistory();
  DowngradeToV6(path);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 6);
  const RunHistory v6 = HistoryStore::Open(path, true).LoadHistory();
  std::string where;
  EXPECT_TRUE(SameHistory(before, v6, &where)) << where;
  for (const WaveRecord& wave : v6.waves) {
    EXPECT_FALSE(wave.multi_fidelity.has_value());
    for (const Particle& p : wave.particles) EXPECT_TRUE(p.low_distance.empty());
  }
  std::string hashes;
  {
    history::Database db(path, /*create=*/false, /*read_only=*/true);
    history::Statement rows(db, "SELECT group_concat(content_hash) FROM wave");
    rows.Step();
    hashes = rows.Text(0);
    rows.Reset();
  }
  {
    HistoryStore store = HistoryStore::Open(path);
    const ResumePoint point = store.BeginResume();
    ASSERT_TRUE(point.has_partial);
    EXPECT_FALSE(point.partial_fidelity.has_value());
  }
  check = HistoryStore::Verify(path);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  history::Database db(path, /*create=*/false, /*read_only=*/true);
  history::Statement rows(db, "SELECT group_concat(content_hash) FROM wave");
  rows.Step();
  EXPECT_EQ(rows.Text(0), hashes) << "the complete wave's checksum stands";
  rows.Reset();
}

// The pattern classes of the mode-loss diagnostic (schema v8) are stored with their wave, read
// back exactly (SameHistory compares them), survive a resume, and are under the wave's checksum.
TEST_F(HistoryIntegrityTest, PatternClassesRoundTripAndAreChecksummed) {
  FakeRunOptions options = SmallRun();
  options.pattern_classes = true;
  const RunHistory history = MakeFakeHistory(options);
  ASSERT_EQ(history.waves[1].pattern_classes.size(), 2u);
  const std::string path = Path("classes.db");
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(options));
    RecordWave(store, history.waves[0], 5);
    RecordWave(store, history.waves[1], 5);
    RecordWave(store, history.waves[2], 5, /*stop_after_batches=*/1);
  }
  const RunHistory loaded = HistoryStore::Open(path, true).LoadHistory();
  ASSERT_EQ(loaded.waves.size(), 3u);
  EXPECT_TRUE(loaded.waves[0].pattern_classes.empty());
  for (int t = 1; t < 3; ++t) {
    EXPECT_EQ(loaded.waves[t].pattern_classes, history.waves[t].pattern_classes) << "wave " << t;
  }
  const ResumePoint point = HistoryStore::Open(path, true).LoadResumePoint();
  ASSERT_EQ(point.completed.size(), 2u);
  EXPECT_EQ(point.completed[1].pattern_classes, history.waves[1].pattern_classes);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();

  // A changed mass (still a valid number) is caught by the wave's checksum; a malformed flag
  // column by the reader.
  for (const char* damage :
       {"UPDATE wave SET pattern_mass = (SELECT pattern_proposal FROM wave WHERE wave = 1) "
        "WHERE wave = 1",
        "UPDATE wave SET pattern_flagged = x'0102' WHERE wave = 1",
        "UPDATE wave SET pattern_bits = x'00' WHERE wave = 1"}) {
    SCOPED_TRACE(damage);
    const std::string damaged = Path("damaged-classes.db");
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(damaged + suffix);
    fs::copy_file(path, damaged);
    if (fs::exists(path + "-wal")) fs::copy_file(path + "-wal", damaged + "-wal");
    Sql(damaged, damage);
    const Error error = Catch([&] { HistoryStore::Open(damaged, true).LoadHistory(); });
    EXPECT_EQ(error.kind(), ErrorKind::kData) << error.what();
    EXPECT_NE(std::string(error.what()).find("wave 2"), std::string::npos) << error.what();
  }
}

// Classes of one or two bits' values (v9) store a mask after each class's bits: a free bit reads
// back as kAnyBit, and a bit set that its mask leaves free is refused.
TEST_F(HistoryIntegrityTest, PatternClassesOfAFewBitsRoundTrip) {
  FakeRunOptions options = SmallRun();
  options.pattern_classes = true;
  RunHistory history = MakeFakeHistory(options);
  std::vector<std::uint8_t> some(history.waves[1].pattern_classes[0].bits.size(), kAnyBit);
  some[1] = 0;
  some.back() = 1;
  history.waves[1].pattern_classes.push_back({some, 0.05, 1e-4, true});
  const std::string path = Path("masked.db");
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(options));
    RecordWave(store, history.waves[0], 5);
    RecordWave(store, history.waves[1], 5);
  }
  const RunHistory loaded = HistoryStore::Open(path, true).LoadHistory();
  ASSERT_EQ(loaded.waves.size(), 2u);
  EXPECT_EQ(loaded.waves[1].pattern_classes, history.waves[1].pattern_classes);
  EXPECT_EQ(PatternText(loaded.waves[1].pattern_classes.back().bits).substr(0, 3), "-0-");
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  // The blob written anew with every bit of the masked class's values set, bits its mask leaves
  // free among them.
  std::string hex;
  for (const PatternClass& c : history.waves[1].pattern_classes) {
    const bool damaged = &c == &history.waves[1].pattern_classes.back();
    for (const bool mask : {false, true}) {
      std::vector<unsigned> bytes((c.bits.size() + 7) / 8, 0);
      for (std::size_t k = 0; k < c.bits.size(); ++k) {
        const bool set = mask ? c.bits[k] != kAnyBit : damaged || c.bits[k] == 1;
        bytes[k / 8] |= (set ? 1U : 0U) << (k % 8);
      }
      for (const unsigned b : bytes) {
        char two[3];
        std::snprintf(two, sizeof two, "%02x", b);
        hex += two;
      }
    }
  }
  Sql(path, "UPDATE wave SET pattern_bits = x'" + hex + "' WHERE wave = 1");
  const Error error = Catch([&] { HistoryStore::Open(path, true).LoadHistory(); });
  EXPECT_EQ(error.kind(), ErrorKind::kData) << error.what();
  EXPECT_NE(std::string(error.what()).find("mask leaves free"), std::string::npos) << error.what();
}

// A resample-move wave's statistics and its particles' ancestors (schema v10) are stored with the
// wave, read back exactly (SameHistory compares them; a rejection wave's are absent), survive a
// resume, and are under the wave's checksum; damage is a data error naming the wave and field.
TEST_F(HistoryIntegrityTest, MoveStatisticsAndAncestorsRoundTripAndAreChecksummed) {
  FakeRunOptions options = SmallRun();
  options.moves = true;
  const RunHistory history = MakeFakeHistory(options);
  ASSERT_EQ(history.waves.size(), 3u);
  ASSERT_TRUE(history.waves[1].moves.has_value());
  const std::string path = Path("moves.db");
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(options));
    for (const WaveRecord& wave : history.waves) RecordWave(store, wave, 5);
    store.Finish(history.summary);
  }
  const RunHistory loaded = HistoryStore::Open(path, true).LoadHistory();
  std::string where;
  EXPECT_TRUE(SameHistory(history, loaded, &where)) << where;
  EXPECT_FALSE(loaded.waves[0].moves.has_value()) << "wave 1 drew afresh";
  EXPECT_EQ(loaded.waves[2].moves, history.waves[2].moves);
  EXPECT_EQ(loaded.waves[0].particles[0].ancestor, -1);
  EXPECT_EQ(loaded.waves[1].particles[1].ancestor, history.waves[0].particles[1].index);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  // The Eve indices (not stored) are derived on load: wave 2's from wave 1, drawn afresh, are its
  // ancestors; wave 3's their ancestors' Eves.
  for (std::size_t t = 1; t < 3; ++t) {
    for (const Particle& p : loaded.waves[t].particles) {
      const auto& previous = loaded.waves[t - 1].particles;
      const auto parent = std::find_if(previous.begin(), previous.end(), [&](const Particle& q) {
        return q.index == p.ancestor;
      });
      ASSERT_NE(parent, previous.end());
      EXPECT_EQ(p.eve, t == 1 ? parent->index : parent->eve);
    }
  }
  // A move wave's particles are numbered by their slot: it may have simulated fewer candidates
  // than it has particles (proposals outside the prior are not simulated).
  {
    RunHistory few = history;
    few.waves[2].candidates = 3;
    for (std::size_t k = 0; k < few.waves[2].particles.size(); ++k) {
      few.waves[2].particles[k].index = static_cast<std::int64_t>(k);
    }
    const std::string slots = Path("slots.db");
    HistoryStore store = HistoryStore::Create(slots, MakeFakeMetadata(options));
    for (const WaveRecord& wave : few.waves) RecordWave(store, wave, 5);
    store.Finish(few.summary);
    EXPECT_TRUE(SameHistory(few, HistoryStore::Open(slots, true).LoadHistory(), &where)) << where;
  }
  // SameHistory itself tells a changed move count or ancestor.
  RunHistory other = loaded;
  other.waves[1].moves->accepted += 1;
  EXPECT_FALSE(SameHistory(history, other, &where));
  other = loaded;
  other.waves[2].particles[0].ancestor += 1;
  EXPECT_FALSE(SameHistory(history, other, &where));

  struct Damage {
    const char* sql;
    const char* field;
  };
  for (const Damage& d : {
           // Valid values, caught by the wave's checksum.
           Damage{"UPDATE wave SET move_rounds = move_rounds + 1 WHERE wave = 1", "content_hash"},
           Damage{"UPDATE particle SET ancestor = NULL WHERE wave = 1 AND candidate = "
                  "(SELECT min(candidate) FROM particle WHERE wave = 1)",
                  "content_hash"},
           // Invalid ones, by the reader.
           Damage{"UPDATE wave SET move_accepted = move_proposed + 1 WHERE wave = 1",
                  "move_accepted"},
           Damage{"UPDATE wave SET move_step = NULL WHERE wave = 1", "move_step"},
           Damage{"UPDATE wave SET move_step = 1.5 WHERE wave = 1", "move_step"},
           Damage{"UPDATE wave SET move_proposed = -3 WHERE wave = 1", "move_proposed"},
           Damage{"UPDATE particle SET ancestor = 1000000 WHERE wave = 1", "ancestor"},
           Damage{"UPDATE particle SET ancestor = 0 WHERE wave = 0", "ancestor"},
       }) {
    SCOPED_TRACE(d.sql);
    const std::string damaged = Path("damaged-moves.db");
    fs::remove(damaged);
    fs::copy_file(path, damaged);
    Sql(damaged, d.sql);
    const Error error = Catch([&] { HistoryStore::Open(damaged, true).LoadHistory(); });
    EXPECT_EQ(error.kind(), ErrorKind::kData) << error.what();
    EXPECT_NE(std::string(error.what()).find(d.field), std::string::npos) << error.what();
    EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos) << error.what();
  }
}

// A v9 file (before resample-move waves) reads as rejection waves whose particles were drawn
// afresh; resuming it upgrades it to v10 without touching its waves' checksums (NULL move columns
// and ancestors are not hashed).
TEST_F(HistoryIntegrityTest, AV9RunReadsAsRejectionWavesAndIsUpgradedToV10OnResume) {
  const std::string path = WriteKilled("killed.db");
  const RunHistory before = HistoryStore::Open(path, true).LoadHistory();
  DowngradeToV9(path);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 9);
  const RunHistory v9 = HistoryStore::Open(path, true).LoadHistory();
  std::string where;
  EXPECT_TRUE(SameHistory(before, v9, &where)) << where;
  for (const WaveRecord& wave : v9.waves) {
    EXPECT_FALSE(wave.moves.has_value());
    for (const Particle& p : wave.particles) EXPECT_EQ(p.ancestor, -1);
  }
  std::string hashes;
  {
    history::Database db(path, /*create=*/false, /*read_only=*/true);
    history::Statement rows(db, "SELECT group_concat(content_hash) FROM wave");
    rows.Step();
    hashes = rows.Text(0);
    rows.Reset();
  }
  {
    HistoryStore store = HistoryStore::Open(path);
    ASSERT_TRUE(store.BeginResume().has_partial);
  }
  check = HistoryStore::Verify(path);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  history::Database db(path, /*create=*/false, /*read_only=*/true);
  history::Statement rows(db, "SELECT group_concat(content_hash) FROM wave");
  rows.Step();
  EXPECT_EQ(rows.Text(0), hashes) << "the complete wave's checksum stands";
  rows.Reset();
}

// A v7 file (before pattern classes) reads as waves without any; resuming it upgrades it to v8
// without touching its waves' checksums (NULL pattern columns are not hashed).
TEST_F(HistoryIntegrityTest, AV7RunReadsWithoutPatternClassesAndIsUpgradedToV8OnResume) {
  const std::string path = WriteKilled("killed.db");
  const RunHistory before = HistoryStore::Open(path, true).LoadHistory();
  DowngradeToV7(path);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 7);
  const RunHistory v7 = HistoryStore::Open(path, true).LoadHistory();
  std::string where;
  EXPECT_TRUE(SameHistory(before, v7, &where)) << where;
  std::string hashes;
  {
    history::Database db(path, /*create=*/false, /*read_only=*/true);
    history::Statement rows(db, "SELECT group_concat(content_hash) FROM wave");
    rows.Step();
    hashes = rows.Text(0);
    rows.Reset();
  }
  {
    HistoryStore store = HistoryStore::Open(path);
    const ResumePoint point = store.BeginResume();
    ASSERT_TRUE(point.has_partial);
  }
  check = HistoryStore::Verify(path);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  history::Database db(path, /*create=*/false, /*read_only=*/true);
  history::Statement rows(db, "SELECT group_concat(content_hash) FROM wave");
  rows.Step();
  EXPECT_EQ(rows.Text(0), hashes) << "the complete wave's checksum stands";
  rows.Reset();
}

// A v2 file (combabc before continuous parameters) reads as a run without reals that ran the
// independent kernel; resuming it upgrades it to v3 with checksums that still protect it.
TEST_F(HistoryIntegrityTest, AV2RunReadsAndIsUpgradedToV3OnResume) {
  const std::string path = WriteKilled("killed.db");
  DowngradeToV2(path);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 2);
  EXPECT_TRUE(check.checksummed);
  const ResumePoint v2 = HistoryStore::Open(path, true).LoadResumePoint();
  ASSERT_TRUE(v2.has_partial);
  ASSERT_FALSE(v2.partial_accepted.empty());
  EXPECT_TRUE(v2.partial_accepted[0].theta.reals.empty());
  RunMetadata metadata = HistoryStore::Open(path, true).LoadMetadata();
  EXPECT_EQ(metadata.schema_version, 2);
  ASSERT_EQ(metadata.experiments.size(), 1u) << "one unnamed experiment before v6";
  EXPECT_EQ(metadata.experiments[0].components, 2);
  EXPECT_TRUE(metadata.reals.empty());
  EXPECT_TRUE(metadata.fingerprint.empty());
  EXPECT_EQ(metadata.proposal.binary, BinaryKernelKind::kIndependent);
  {
    HistoryStore store = HistoryStore::Open(path);
    const ResumePoint point = store.BeginResume();
    EXPECT_EQ(point.partial_next_index, v2.partial_next_index);
    EXPECT_EQ(point.partial_accepted.size(), v2.partial_accepted.size());
  }
  check = HistoryStore::Verify(path);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  metadata = HistoryStore::Open(path, true).LoadMetadata();
  EXPECT_EQ(metadata.tempering_form, "") << "an upgraded run did not record its tempering form";
  EXPECT_EQ(metadata.proposal.binary, BinaryKernelKind::kIndependent);
  Sql(path,
      "UPDATE particle SET weight = 0.5 WHERE wave = 0 AND candidate = (SELECT min(candidate) FROM "
      "particle WHERE wave = 0)");
  ExpectDataError(
      Catch([&] { HistoryStore::Open(path, true).LoadHistory(); }), path, "wave 1, content_hash");
}

// A v3 file (before failed simulations) reads as a run without failures; resuming it upgrades it to
// v4, whose checksums then cover the failure table too.
TEST_F(HistoryIntegrityTest, AV3RunReadsAndIsUpgradedToV4OnResume) {
  const std::string path = WriteKilled("killed.db");
  DowngradeToV3(path);
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 3);
  const ResumePoint v3 = HistoryStore::Open(path, true).LoadResumePoint();
  ASSERT_TRUE(v3.has_partial);
  EXPECT_TRUE(v3.partial_failures.empty());
  {
    HistoryStore store = HistoryStore::Open(path);
    const ResumePoint point = store.BeginResume();
    EXPECT_EQ(point.partial_next_index, v3.partial_next_index);
    EXPECT_EQ(point.partial_accepted.size(), v3.partial_accepted.size());
  }
  check = HistoryStore::Verify(path);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  Sql(path, "INSERT INTO failure (wave, candidate, reason) VALUES (0, 0, 'forged')");
  ExpectDataError(
      Catch([&] { HistoryStore::Open(path, true).LoadHistory(); }), path, "wave 1, failures");
}

// Waves deleted by hand after the run (issue 20, D2): the run recorded how many wave rows it wrote
// (v5: meta wave_count, under run_state_hash), and a finished run how many complete waves it had
// (waves_completed): an earlier wave never reads as the posterior.
TEST_F(HistoryIntegrityTest, WavesDeletedByHandAreRefused) {
  const std::string path = WriteFinished("finished.db");
  Sql(path, "DELETE FROM particle WHERE wave >= 2; DELETE FROM wave WHERE wave >= 2; VACUUM");
  ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, "meta.wave_count");
  ExpectDataError(Catch([&] { HistoryStore::Open(path); }), path, "meta.wave_count");
  HistoryCheck check = HistoryStore::Verify(path);
  ASSERT_FALSE(check.problems.empty());
  EXPECT_NE(check.problems.front().find("recorded 3 waves, the file holds 2"), std::string::npos)
      << check.problems.front();

  // A v4 file has no wave count: its finished run's waves_completed tells.
  const std::string v4 = WriteFinished("v4.db");
  DowngradeToV4(v4);
  EXPECT_TRUE(HistoryStore::Verify(v4).problems.empty());
  Sql(v4, "DELETE FROM particle WHERE wave >= 2; DELETE FROM wave WHERE wave >= 2");
  ExpectDataError(Catch([&] { HistoryStore::Open(v4, true); }), v4, "run.waves_completed");
  check = HistoryStore::Verify(v4);
  ASSERT_FALSE(check.problems.empty());
  EXPECT_NE(check.problems.front().find("ended with 3 complete waves, the file holds only 2"),
            std::string::npos)
      << check.problems.front();

  // A killed run's wave in progress, deleted, is missed as well: resume would redo it silently.
  const std::string killed = WriteKilled("killed.db");
  Sql(killed, "DELETE FROM particle WHERE wave = 1; DELETE FROM wave WHERE wave = 1");
  ExpectDataError(Catch([&] { HistoryStore::Open(killed); }), killed, "meta.wave_count");
}

TEST_F(HistoryIntegrityTest, OrphanParticlesAndFailuresAreRefused) {
  const std::string path = WriteFinished("finished.db");
  // Copies of wave 1's particles under a wave that has no row: no checksum covers them.
  Sql(path,
      "INSERT INTO particle (wave, candidate, bits) SELECT 7, candidate, bits FROM particle WHERE "
      "wave = 0");
  ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, "particle");
  const HistoryCheck check = HistoryStore::Verify(path);
  ASSERT_EQ(check.problems.size(), 1u) << check.problems.front();
  EXPECT_NE(check.problems.front().find("wave '7', which has no wave row"), std::string::npos)
      << check.problems.front();

  const std::string failures = WriteFinished("failures.db");
  Sql(failures, "INSERT INTO failure (wave, candidate, reason) VALUES (3, 0, 'forged')");
  ExpectDataError(Catch([&] { HistoryStore::Open(failures, true); }), failures, "failure");

  // A wave number between two waves (1.5) is no wave either; verify's full pass finds it.
  const std::string odd = WriteFinished("odd.db");
  Sql(odd,
      "INSERT INTO particle (wave, candidate, bits) SELECT 1.5, candidate, bits FROM particle "
      "WHERE wave = 0");
  const HistoryCheck odd_check = HistoryStore::Verify(odd);
  ASSERT_FALSE(odd_check.problems.empty());
  EXPECT_NE(odd_check.problems.front().find("wave '1.5'"), std::string::npos)
      << odd_check.problems.front();
}

// A trigger, view or index that combabc did not create (D3) could change the history behind its
// back (a trigger deleting every wave at the resume's first insert): refused on open, before any
// write, and reported by verify.
TEST_F(HistoryIntegrityTest, SchemaObjectsCombabcDidNotCreateAreRefused) {
  struct Case {
    const char* sql;
    const char* field;
  };
  for (const Case& c : {
           Case{"CREATE TRIGGER boom AFTER INSERT ON particle BEGIN DELETE FROM wave; END",
                "trigger boom"},
           Case{"CREATE VIEW posterior AS SELECT * FROM particle", "view posterior"},
           Case{"CREATE INDEX by_weight ON particle (weight)", "index by_weight"},
           Case{"CREATE TABLE notes (text TEXT)", "table notes"},
       }) {
    SCOPED_TRACE(c.sql);
    const std::string path = WriteKilled("killed.db");
    Sql(path, c.sql);
    ExpectDataError(Catch([&] { HistoryStore::Open(path, true); }), path, c.field);
    ExpectDataError(Catch([&] { HistoryStore::Open(path); }), path, c.field);
    const HistoryCheck check = HistoryStore::Verify(path);
    ASSERT_EQ(check.problems.size(), 1u) << check.problems.front();
    EXPECT_NE(check.problems.front().find("combabc did not create"), std::string::npos)
        << check.problems.front();
    fs::remove(path);
  }
}

// SQLite's own statistics (ANALYZE, PRAGMA optimize) change no row: such a file is still read,
// and older versions' schemas (no failure table before v4) are what they were.
TEST_F(HistoryIntegrityTest, SqliteStatisticsAndOlderSchemasAreNotForeign) {
  const std::string path = WriteFinished("finished.db");
  Sql(path, "ANALYZE");
  EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
  EXPECT_EQ(HistoryStore::Open(path, true).LoadHistory().waves.size(), 3u);
  const std::string v3 = WriteFinished("v3.db");
  DowngradeToV3(v3);
  const HistoryCheck check = HistoryStore::Verify(v3);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, 3);
}

// The wave count follows every change a writer makes: a resume that drops a wave started without
// any batch, and the waves it adds, verify clean; a v4 file resumed is upgraded and counted.
TEST_F(HistoryIntegrityTest, TheWaveCountFollowsResumeAndUpgrade) {
  const std::string path = Path("started.db");
  const RunHistory history = MakeFakeHistory(SmallRun());
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], 5);
    store.OnWaveStart(history.waves[1]);  // killed before its first batch
  }
  EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
  {
    HistoryStore store = HistoryStore::Open(path);
    EXPECT_FALSE(store.BeginResume().has_partial);
    RecordWave(store, history.waves[1], 5);
    RunSummary summary = history.summary;
    summary.waves_completed = 2;
    store.Finish(summary);
  }
  HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.waves, 2);

  const std::string v4 = WriteKilled("v4.db");
  DowngradeToV4(v4);
  { HistoryStore::Open(v4).BeginResume(); }
  check = HistoryStore::Verify(v4);
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  Sql(v4, "DELETE FROM particle WHERE wave = 1; DELETE FROM wave WHERE wave = 1");
  ExpectDataError(Catch([&] { HistoryStore::Open(v4, true); }), v4, "meta.wave_count");
}

}  // namespace
}  // namespace combabc
