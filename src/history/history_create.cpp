// Creating and opening a run history, and the schema itself (docs/history.md, version 10).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>

#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/params/binary_space.hpp"
#include "history/history_impl.hpp"

#ifndef COMBABC_VERSION
#define COMBABC_VERSION "unknown"
#endif

namespace combabc {
namespace {

// What to do instead is named: the CLI's and the Python module's run and enumerate take the flag
// (--overwrite / overwrite=True) and the folder (-o DIR / output_directory=).
constexpr const char* kExistsMessage =
    "cannot create run history: file exists (refusing to replace it; use --overwrite to replace "
    "it, or write elsewhere with -o DIR)";

namespace fs = std::filesystem;
using history::Statement;
using history::Transaction;

// Version 10 of the schema (version 1 lacked wave.discarded, wave.content_hash and the checksums in
// meta; version 2 the tables real and proposal, the reals columns and the fingerprint; version 3
// the table failure and wave.failures, created apart as kSchemaV4Tables; version 4 the meta row
// wave_count, which adds no table; version 5 the table experiment, created apart as
// kSchemaV6Tables; version 6 the multi-fidelity columns, added to an older file by
// kSchemaV7Columns; version 7 the pattern classes, added by kSchemaV8Columns; version 9 the
// resample-move columns, added by kSchemaV10Columns). Every table and
// index here is listed in ExpectedObjects (history_verify.cpp), which refuses any other schema
// object in a history. Vectors of doubles are BLOBs of little-endian binary64 (exact, and +-inf /
// NaN survive, which REAL columns and JSON would not guarantee); bits are packed.
constexpr const char* kSchema = R"sql(
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE run (
  id INTEGER PRIMARY KEY CHECK (id = 1),
  status TEXT NOT NULL,
  config_text TEXT NOT NULL,
  config_path TEXT NOT NULL,
  combabc_version TEXT NOT NULL,
  git_hash TEXT NOT NULL,
  seed TEXT NOT NULL,
  threads INTEGER NOT NULL,
  start_time TEXT NOT NULL,
  end_time TEXT NOT NULL,
  termination TEXT NOT NULL,
  message TEXT NOT NULL,
  resume_count INTEGER NOT NULL,
  estimator TEXT NOT NULL,
  dimension INTEGER NOT NULL,
  position_unit TEXT NOT NULL,
  waves_completed INTEGER,
  simulations INTEGER,
  simulations_discarded INTEGER,
  wall_seconds REAL
);
CREATE TABLE bit (bit INTEGER PRIMARY KEY, name TEXT NOT NULL, prior REAL NOT NULL);
CREATE TABLE component (
  component INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  kind TEXT NOT NULL,
  required REAL NOT NULL
);
CREATE TABLE output_position (i INTEGER PRIMARY KEY, position REAL NOT NULL);
CREATE TABLE measured (i INTEGER PRIMARY KEY, position REAL NOT NULL, value REAL NOT NULL);
CREATE TABLE wave (
  wave INTEGER PRIMARY KEY,
  thresholds BLOB,
  phi REAL,
  proposal BLOB,
  started_at TEXT NOT NULL,
  accepted_needed INTEGER NOT NULL DEFAULT 0,
  next_index INTEGER NOT NULL DEFAULT 0,
  accepted_so_far INTEGER NOT NULL DEFAULT 0,
  total_simulations INTEGER NOT NULL DEFAULT 0,
  ended INTEGER NOT NULL DEFAULT 0,
  complete INTEGER NOT NULL DEFAULT 0,
  candidates INTEGER,
  accepted INTEGER,
  acceptance_rate REAL,
  marginals_paper BLOB,
  marginals_importance BLOB,
  ess REAL,
  distinct_count INTEGER,
  wall_seconds REAL,
  ended_at TEXT,
  discarded INTEGER NOT NULL DEFAULT 0,
  content_hash TEXT,
  reals_mean BLOB,
  reals_sd BLOB,
  failures INTEGER NOT NULL DEFAULT 0,
  continue_if_accepted REAL,
  continue_if_rejected REAL,
  expensive_simulations INTEGER,
  cheap_seconds REAL,
  expensive_seconds REAL,
  unkept_false_positives INTEGER,
  unkept_false_positive_log_w2 REAL,
  next_continue_if_accepted REAL,
  next_continue_if_rejected REAL,
  cost_ratio REAL,
  pattern_bits BLOB,
  pattern_mass BLOB,
  pattern_proposal BLOB,
  pattern_flagged BLOB,
  move_survivor_ess REAL,
  move_step REAL,
  move_rounds INTEGER,
  move_proposed INTEGER,
  move_accepted INTEGER,
  move_independent_proposed INTEGER,
  move_independent_accepted INTEGER
);
CREATE TABLE particle (
  wave INTEGER NOT NULL REFERENCES wave (wave),
  candidate INTEGER NOT NULL,
  bits BLOB NOT NULL,
  log_weight REAL,
  weight REAL,
  distance BLOB,
  output BLOB,
  reals BLOB,
  multiplier REAL,
  confirmed INTEGER,
  low_distance BLOB,
  ancestor INTEGER,
  PRIMARY KEY (wave, candidate)
);
)sql";

// Added by version 3 (also when an older file is upgraded).
constexpr const char* kSchemaV3Tables = R"sql(
CREATE TABLE real (
  i INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  kind TEXT NOT NULL,
  low REAL NOT NULL,
  high REAL NOT NULL,
  mean REAL NOT NULL,
  sd REAL NOT NULL
);
CREATE TABLE proposal (
  id INTEGER PRIMARY KEY CHECK (id = 1),
  binary_kernel TEXT NOT NULL,
  min_correlation REAL NOT NULL,
  max_predecessors INTEGER NOT NULL,
  ridge REAL NOT NULL,
  min_marginal REAL NOT NULL,
  clip REAL NOT NULL,
  continuous_kernel TEXT NOT NULL,
  scale REAL NOT NULL,
  tempering_form TEXT NOT NULL
);
)sql";

// Added by version 4 (also when an older file is upgraded): the failed simulations, one row per
// candidate whose simulation failed, with its reason.
constexpr const char* kSchemaV4Tables = R"sql(
CREATE TABLE failure (
  wave INTEGER NOT NULL REFERENCES wave (wave),
  candidate INTEGER NOT NULL,
  reason TEXT NOT NULL,
  PRIMARY KEY (wave, candidate)
);
)sql";

// Added by version 6 (also when an older file is upgraded): the run's experiments, in order, each
// as the sizes of its slices of output_position, measured and component (which hold every
// experiment's rows, experiment after experiment). Never empty: a run of one experiment has one
// row, named "" when the configuration named none.
constexpr const char* kSchemaV6Tables = R"sql(
CREATE TABLE experiment (
  e INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  description TEXT NOT NULL,
  outputs INTEGER NOT NULL,
  measured INTEGER NOT NULL,
  components INTEGER NOT NULL
);
)sql";

// Added by version 7 to an older file (a new one has them in kSchema): the multi-fidelity columns,
// NULL in a single-fidelity run (docs/history.md, "Multi-fidelity runs").
constexpr const char* kSchemaV7Columns = R"sql(
ALTER TABLE wave ADD COLUMN continue_if_accepted REAL;
ALTER TABLE wave ADD COLUMN continue_if_rejected REAL;
ALTER TABLE wave ADD COLUMN expensive_simulations INTEGER;
ALTER TABLE wave ADD COLUMN cheap_seconds REAL;
ALTER TABLE wave ADD COLUMN expensive_seconds REAL;
ALTER TABLE wave ADD COLUMN unkept_false_positives INTEGER;
ALTER TABLE wave ADD COLUMN unkept_false_positive_log_w2 REAL;
ALTER TABLE wave ADD COLUMN next_continue_if_accepted REAL;
ALTER TABLE wave ADD COLUMN next_continue_if_rejected REAL;
ALTER TABLE wave ADD COLUMN cost_ratio REAL;
ALTER TABLE particle ADD COLUMN multiplier REAL;
ALTER TABLE particle ADD COLUMN confirmed INTEGER;
ALTER TABLE particle ADD COLUMN low_distance BLOB;
)sql";

// Added by version 8 to an older file (a new one has them in kSchema): each wave's pattern classes
// (WaveRecord::pattern_classes; docs/history.md, "Mode loss"), NULL in a wave that has none.
constexpr const char* kSchemaV8Columns = R"sql(
ALTER TABLE wave ADD COLUMN pattern_bits BLOB;
ALTER TABLE wave ADD COLUMN pattern_mass BLOB;
ALTER TABLE wave ADD COLUMN pattern_proposal BLOB;
ALTER TABLE wave ADD COLUMN pattern_flagged BLOB;
)sql";

// Added by version 10 to an older file (a new one has them in kSchema): what a resample-move
// wave's moves did (WaveRecord::moves) and each of its particles' ancestor (Particle::ancestor);
// NULL in a rejection wave and for a particle drawn afresh (docs/history.md, "Resample-move").
constexpr const char* kSchemaV10Columns = R"sql(
ALTER TABLE wave ADD COLUMN move_survivor_ess REAL;
ALTER TABLE wave ADD COLUMN move_step REAL;
ALTER TABLE wave ADD COLUMN move_rounds INTEGER;
ALTER TABLE wave ADD COLUMN move_proposed INTEGER;
ALTER TABLE wave ADD COLUMN move_accepted INTEGER;
ALTER TABLE wave ADD COLUMN move_independent_proposed INTEGER;
ALTER TABLE wave ADD COLUMN move_independent_accepted INTEGER;
ALTER TABLE particle ADD COLUMN ancestor INTEGER;
)sql";

// What an older file upgraded to v6 (and a RunMetadata without experiments) holds: one unnamed
// experiment covering every output, measured point and component.
constexpr const char* kInsertSingleExperiment = R"sql(
INSERT INTO experiment (e, name, description, outputs, measured, components)
VALUES (0, '', '', (SELECT count(*) FROM output_position), (SELECT count(*) FROM measured),
  (SELECT count(*) FROM component))
)sql";

void WriteProposal(history::Database& db, const ProposalOptions& p, const std::string& form) {
  Statement s(db, R"sql(
    INSERT OR REPLACE INTO proposal (id, binary_kernel, min_correlation, max_predecessors, ridge,
      min_marginal, clip, continuous_kernel, scale, tempering_form)
    VALUES (1, ?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9))sql");
  s.Bind(1, std::string(ToString(p.binary)))
      .Bind(2, p.logistic.min_correlation)
      .Bind(3, p.logistic.max_predecessors)
      .Bind(4, p.logistic.ridge)
      .Bind(5, p.logistic.min_marginal)
      .Bind(6, p.logistic.clip)
      .Bind(7, std::string(ToString(p.continuous)))
      .Bind(8, p.scale)
      .Bind(9, form)
      .Run();
}

const char* KindName(ComponentKind kind) { return ToString(kind); }

void RemoveRunFiles(const std::string& path) {
  std::error_code ignored;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) fs::remove(path + suffix, ignored);
}

void WriteMetadata(history::Database& db, const RunMetadata& m) {
  Statement meta(db, "INSERT INTO meta (key, value) VALUES (?1, ?2)");
  meta.Bind(1, std::string("format")).Bind(2, std::string("combabc-history")).Run();
  meta.Bind(1, std::string("schema_version")).Bind(2, std::to_string(kHistorySchemaVersion)).Run();

  Statement run(db, R"sql(
    INSERT INTO run (id, status, config_text, config_path, combabc_version, git_hash, seed,
      threads, start_time, end_time, termination, message, resume_count, estimator, dimension,
      position_unit)
    VALUES (1, ?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, '', '', '', 0, ?9, ?10, ?11))sql");
  run.Bind(1, std::string(ToString(RunStatus::kRunning)))
      .Bind(2, m.config_text)
      .Bind(3, m.config_path)
      .Bind(4, m.combabc_version.empty() ? std::string(COMBABC_VERSION) : m.combabc_version)
      .Bind(5, m.git_hash)
      .Bind(6, std::to_string(m.seed))  // TEXT: a uint64 seed does not fit SQLite's int64
      .Bind(7, m.threads)
      .Bind(8, m.start_time.empty() ? history::UtcNow() : m.start_time)
      .Bind(9, m.estimator)
      .Bind(10, m.dimension)
      .Bind(11, m.position_unit)
      .Run();

  Statement bit(db, "INSERT INTO bit (bit, name, prior) VALUES (?1, ?2, ?3)");
  for (int k = 0; k < m.dimension; ++k) {
    const auto K = static_cast<std::size_t>(k);
    bit.Bind(1, k)
        .Bind(2, K < m.bit_names.size() ? m.bit_names[K] : "bit " + std::to_string(k + 1))
        .Bind(3, K < m.bit_prior_one.size() ? m.bit_prior_one[K] : 0.5)
        .Run();
  }
  Statement component(
      db, "INSERT INTO component (component, name, kind, required) VALUES (?1, ?2, ?3, ?4)");
  for (std::size_t c = 0; c < m.distance_components.size(); ++c) {
    const DistanceComponent& dc = m.distance_components[c];
    component.Bind(1, static_cast<std::int64_t>(c))
        .Bind(2, dc.name)
        .Bind(3, std::string(KindName(dc.kind)))
        .Bind(4, dc.required)
        .Run();
  }
  Statement position(db, "INSERT INTO output_position (i, position) VALUES (?1, ?2)");
  for (std::size_t i = 0; i < m.output_positions.size(); ++i) {
    position.Bind(1, static_cast<std::int64_t>(i)).Bind(2, m.output_positions[i]).Run();
  }
  Statement measured(db, "INSERT INTO measured (i, position, value) VALUES (?1, ?2, ?3)");
  for (std::size_t i = 0; i < m.measured.positions.size(); ++i) {
    measured.Bind(1, static_cast<std::int64_t>(i))
        .Bind(2, m.measured.positions[i])
        .Bind(3, m.measured.values[i])
        .Run();
  }
  Statement real(db, R"sql(
    INSERT INTO real (i, name, kind, low, high, mean, sd) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7))sql");
  for (std::size_t i = 0; i < m.reals.size(); ++i) {
    const ContinuousPrior& prior = m.reals[i].prior;
    real.Bind(1, static_cast<std::int64_t>(i))
        .Bind(2, m.reals[i].name)
        .Bind(3, std::string(ToString(prior.kind)))
        .Bind(4, prior.low)
        .Bind(5, prior.high)
        .Bind(6, prior.mean)
        .Bind(7, prior.sd)
        .Run();
  }
  // The kernel the run used: a default (kAuto) not yet resolved is resolved for the run's space
  // (its bits count only where their prior is neither 0 nor 1).
  const bool uncertain =
      m.bit_prior_one.empty() ? m.dimension > 0 : AnyUncertainBit(m.bit_prior_one);
  WriteProposal(db, ResolvedProposal(m.proposal, uncertain && !m.reals.empty()), m.tempering_form);
  for (const auto& [part, digest] : m.fingerprint) {
    meta.Bind(1, "fingerprint_" + part).Bind(2, digest).Run();
  }
  if (m.experiments.empty()) {
    db.Exec(kInsertSingleExperiment);
  } else {
    Statement experiment(db, R"sql(
      INSERT INTO experiment (e, name, description, outputs, measured, components)
      VALUES (?1, ?2, ?3, ?4, ?5, ?6))sql");
    for (std::size_t e = 0; e < m.experiments.size(); ++e) {
      const StoredExperiment& x = m.experiments[e];
      experiment.Bind(1, static_cast<std::int64_t>(e))
          .Bind(2, x.name)
          .Bind(3, x.description)
          .Bind(4, x.outputs)
          .Bind(5, x.measured)
          .Bind(6, x.components)
          .Run();
    }
  }
}

// The experiments must cut output_positions, measured and distance_components into consecutive
// slices exactly (kSoftware otherwise: the caller built an inconsistent RunMetadata).
void CheckExperiments(const RunMetadata& m, const std::string& path) {
  if (m.experiments.empty()) return;  // one unnamed experiment holding everything
  std::int64_t outputs = 0;
  std::int64_t measured = 0;
  std::int64_t components = 0;
  std::set<std::string> names;
  for (std::size_t e = 0; e < m.experiments.size(); ++e) {
    const StoredExperiment& x = m.experiments[e];
    const std::string which =
        "RunMetadata::experiments[" + std::to_string(e) + "] '" + x.name + "'";
    if (x.outputs < 0 || x.measured < 0 || x.components < 0) {
      throw Error(ErrorKind::kSoftware, which + " has a negative count", path);
    }
    if (!names.insert(x.name).second) {
      throw Error(ErrorKind::kSoftware, which + ": the name repeats an earlier experiment's", path);
    }
    outputs += x.outputs;
    measured += x.measured;
    components += x.components;
  }
  auto check = [&](std::int64_t sum, std::size_t size, const char* what) {
    if (sum != static_cast<std::int64_t>(size)) {
      throw Error(ErrorKind::kSoftware,
                  std::string("RunMetadata::experiments: their ") + what + " add up to " +
                      std::to_string(sum) + ", the run has " + std::to_string(size),
                  path);
    }
  };
  check(outputs, m.output_positions.size(), "outputs");
  check(measured, m.measured.positions.size(), "measured points");
  check(components, m.distance_components.size(), "distance components");
}

// v5: the number of wave rows (meta row wave_count), then the run state's checksum over it.
void WriteRunStateHash(history::Database& db, int schema_version) {
  if (schema_version >= 5) {
    db.Exec(
        "INSERT OR REPLACE INTO meta (key, value) "
        "VALUES ('wave_count', CAST((SELECT count(*) FROM wave) AS TEXT))");
  }
  Statement store(db, "INSERT OR REPLACE INTO meta (key, value) VALUES (?1, ?2)");
  store.Bind(1, std::string("run_state_hash"))
      .Bind(2, history::HexDigest(history::RunStateHash(db, schema_version)))
      .Run();
}

void WriteRunHashes(history::Database& db, int schema_version) {
  Statement store(db, "INSERT OR REPLACE INTO meta (key, value) VALUES (?1, ?2)");
  store.Bind(1, std::string("metadata_hash"))
      .Bind(2, history::HexDigest(history::MetadataHash(db, schema_version)))
      .Run();
  WriteRunStateHash(db, schema_version);
}

// WAL: a commit appends to the -wal file, so a process killed at any moment leaves every committed
// batch readable (the next open replays the WAL). synchronous=NORMAL skips the fsync per commit:
// committed batches survive a process kill, though not a power loss, which we accept for speed.
void SetWriteMode(history::Database& db) {
  db.Exec("PRAGMA journal_mode = WAL");
  db.Exec("PRAGMA synchronous = NORMAL");
}

}  // namespace

HistoryStore::HistoryStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HistoryStore::HistoryStore(HistoryStore&& other) noexcept = default;
HistoryStore& HistoryStore::operator=(HistoryStore&& other) noexcept = default;
HistoryStore::~HistoryStore() = default;

const std::string& HistoryStore::path() const { return impl_->db.path(); }

HistoryStore HistoryStore::Create(const std::string& path,
                                  const RunMetadata& metadata,
                                  bool overwrite) {
  // Zero bits: a continuous-only run, which has reals.
  if (metadata.dimension < 0 || (metadata.dimension == 0 && metadata.reals.empty())) {
    throw Error(ErrorKind::kSoftware,
                "RunMetadata::dimension must be >= 1, or 0 with continuous parameters",
                path);
  }
  if (!metadata.bit_prior_one.empty() &&
      metadata.bit_prior_one.size() != static_cast<std::size_t>(metadata.dimension)) {
    throw Error(
        ErrorKind::kSoftware, "RunMetadata::bit_prior_one must be empty or one per bit", path);
  }
  if (metadata.measured.positions.size() != metadata.measured.values.size()) {
    throw Error(ErrorKind::kSoftware, "measured positions and values differ in length", path);
  }
  CheckExperiments(metadata, path);
  for (const auto& [part, digest] : metadata.fingerprint) {
    // A part names a meta key: lower-case words; a digest is what HexDigest writes.
    const bool named =
        !part.empty() && part.find_first_not_of("abcdefghijklmnopqrstuvwxyz_") == std::string::npos;
    if (!named || !history::ParseHexDigest(digest)) {
      throw Error(ErrorKind::kSoftware,
                  std::string("RunMetadata::fingerprint: bad part '")
                      .append(part)
                      .append("' = '")
                      .append(digest)
                      .append("'"),
                  path);
    }
  }
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error(ErrorKind::kCantCreate,
                "cannot create run history: directory " + dir.string() + " does not exist",
                path);
  }
  // --overwrite replaces a regular file only; a device or FIFO at the path is never replaced.
  if (ClassifyOutputPath(path) == OutputPathKind::kStream) {
    throw Error(ErrorKind::kCantCreate,
                "cannot create run history: the path is a device or FIFO (refusing to replace "
                "it; choose a file path)",
                path);
  }
  if (fs::exists(target, ec) && !overwrite) {
    throw Error(ErrorKind::kCantCreate, kExistsMessage, path);
  }
  // Built under a temporary name and moved into place complete: a process killed while creating
  // never leaves a half-made RUN.sqlite (at worst a stray .creating file).
  const std::string temp =
      (dir / ("." + target.filename().string() + ".creating-" + std::to_string(::getpid())))
          .string();
  RemoveRunFiles(temp);
  // Creating the file ourselves gives the OS's reason (permission, read-only file system, ...),
  // which SQLite reduces to "unable to open database file".
  std::FILE* file = std::fopen(temp.c_str(), "wx");
  if (file == nullptr) {
    throw Error(ErrorKind::kCantCreate,
                std::string("cannot create run history: ") + std::strerror(errno),
                path);
  }
  std::fclose(file);
  // Locked before it gets its name: the file is never visible unlocked while this run writes it.
  history::RunLock lock = history::RunLock::Acquire(temp);
  // Replacing a history that another process is still writing would pull it from under that run.
  history::RunLock replaced;
  try {
    if (overwrite && fs::exists(target, ec)) replaced = history::RunLock::Acquire(path);
    {
      history::Database db(temp, /*create=*/true, /*read_only=*/false);
      Transaction transaction(db);
      db.Exec(kSchema);
      db.Exec(kSchemaV3Tables);
      db.Exec(kSchemaV4Tables);
      db.Exec(kSchemaV6Tables);
      WriteMetadata(db, metadata);
      WriteRunHashes(db, kHistorySchemaVersion);
      db.Exec(("PRAGMA application_id = " + std::to_string(kHistoryApplicationId)).c_str());
      db.Exec(("PRAGMA user_version = " + std::to_string(kHistorySchemaVersion)).c_str());
      transaction.Commit();
    }
    // A -wal left by an older file of this name must not be replayed into the new one.
    for (const char* suffix : {"-wal", "-shm", "-journal"}) fs::remove(path + suffix, ec);
    if (overwrite) {
      fs::rename(temp, target);
    } else if (::link(temp.c_str(), path.c_str()) != 0) {
      // link() fails if the name was taken meanwhile: two runs cannot both claim one file.
      const int error = errno;
      if (error == EEXIST) {
        throw Error(ErrorKind::kCantCreate, kExistsMessage, path);
      }
      fs::rename(temp, target);  // a file system without hard links
    }
    RemoveRunFiles(temp);
  } catch (const Error& error) {
    RemoveRunFiles(temp);
    throw Error(
        ErrorKind::kCantCreate, error.message(), error.file().empty() ? path : error.file());
  } catch (const fs::filesystem_error& error) {
    RemoveRunFiles(temp);
    throw Error(
        ErrorKind::kCantCreate, "cannot create run history: " + error.code().message(), path);
  } catch (...) {
    RemoveRunFiles(temp);
    throw;
  }
  auto impl = std::make_unique<Impl>(path, /*read_only=*/false, std::move(lock));
  SetWriteMode(impl->db);
  impl->write_ready = true;
  impl->CheckMetadata();
  return HistoryStore(std::move(impl));
}

HistoryStore HistoryStore::Open(const std::string& path, bool read_only) {
  return OpenFile(path, read_only, /*check=*/true);
}

HistoryStore HistoryStore::OpenFile(const std::string& path, bool read_only, bool check) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(ErrorKind::kNoInput, "no such run history", path);
  if (fs::is_directory(path, ec)) {
    throw Error(ErrorKind::kNoInput, "is a directory, not a run history", path);
  }
  // A writer (resume) takes the run's lock before anything else; readers need none.
  history::RunLock lock = read_only ? history::RunLock() : history::RunLock::Acquire(path);
  auto impl = std::make_unique<Impl>(path, read_only, std::move(lock));
  history::Database& db = impl->db;
  const std::int64_t application_id = db.QueryInt("PRAGMA application_id");
  const std::int64_t version = db.QueryInt("PRAGMA user_version");
  if (application_id != kHistoryApplicationId || version < 1) {
    throw Error(ErrorKind::kData, "not a combabc run history", path);
  }
  if (version > kHistorySchemaVersion) {
    throw Error(ErrorKind::kData,
                "run history schema version " + std::to_string(version) +
                    " is newer than this combabc reads (" + std::to_string(kHistorySchemaVersion) +
                    "); use a newer combabc",
                path);
  }
  impl->schema_version = static_cast<int>(version);
  if (!check) return HistoryStore(std::move(impl));
  const std::vector<std::string> problems = impl->StorageProblems(/*full=*/false);
  if (!problems.empty()) {
    throw Error(
        ErrorKind::kData, "corrupt run history (SQLite check: " + problems.front() + ")", path);
  }
  {
    history::ReadSnapshot snapshot(db);
    impl->CheckSchemaObjects();
    impl->CheckMetadata();
    impl->CheckRunState();
    impl->CheckWaveSet(/*full=*/false);
  }
  // A writer changes nothing yet (journal mode, upgrade): not before its first write, so that a
  // resume refused after opening (its fingerprint) leaves the file as it was.
  return HistoryStore(std::move(impl));
}

void HistoryStore::Impl::PrepareWrite() {
  if (write_ready) return;
  SetWriteMode(db);
  if (schema_version < kHistorySchemaVersion) MigrateToCurrent();
  write_ready = true;
}

void HistoryStore::Impl::StoreRunHashes() { WriteRunHashes(db, schema_version); }

void HistoryStore::Impl::StoreRunStateHash() { WriteRunStateHash(db, schema_version); }

void HistoryStore::Impl::MigrateToCurrent() {
  // Only what an older file can be trusted with: its structure and (v2) its checksums were checked
  // on open; the new checksums protect it from here on. A v1 run's earlier waves did not record
  // their overshoot (0). An older run has no reals, ran the default (independent) kernels, and
  // recorded neither its tempering form (left empty) nor a fingerprint (resume then checks none),
  // nor (before v4) any failed simulation; (before v6) it had a single, unnamed experiment; and
  // (before v7) it ran one simulator only (its multi-fidelity columns stay NULL); and (before v8)
  // it recorded no pattern classes (the columns stay NULL: none). v9 adds no column: a v8 wave's
  // classes are whole patterns, stored as v9 stores a wave without classes of a few bits. Before
  // v10 every wave was a rejection wave (its move columns and its particles' ancestors stay NULL).
  Transaction transaction(db);
  const int from = schema_version;
  if (schema_version < 2) {
    db.Exec(R"sql(
      ALTER TABLE wave ADD COLUMN discarded INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE wave ADD COLUMN content_hash TEXT;)sql");
  }
  if (schema_version < 3) {
    db.Exec(R"sql(
      ALTER TABLE wave ADD COLUMN reals_mean BLOB;
      ALTER TABLE wave ADD COLUMN reals_sd BLOB;
      ALTER TABLE particle ADD COLUMN reals BLOB;)sql");
    db.Exec(kSchemaV3Tables);
    // Runs before v3 had no reals: the default kernel was, and resolves to, independent.
    WriteProposal(db, ResolvedProposal(ProposalOptions{}, /*mixed=*/false), "");
  }
  if (schema_version < 4) {
    // An older run recorded no failures: its simulators could not fail without ending the run.
    db.Exec("ALTER TABLE wave ADD COLUMN failures INTEGER NOT NULL DEFAULT 0");
    db.Exec(kSchemaV4Tables);
  }
  // v5 adds the meta row wave_count, written with the run state's checksum below.
  if (schema_version < 6) {
    // An older run had one experiment: every output, measured point and component is its.
    db.Exec(kSchemaV6Tables);
    db.Exec(kInsertSingleExperiment);
  }
  if (schema_version < 7) db.Exec(kSchemaV7Columns);
  if (schema_version < 8) db.Exec(kSchemaV8Columns);
  if (schema_version < 10) db.Exec(kSchemaV10Columns);
  db.Exec(("UPDATE meta SET value = '" + std::to_string(kHistorySchemaVersion) +
           "' WHERE key = 'schema_version'; PRAGMA user_version = " +
           std::to_string(kHistorySchemaVersion))
              .c_str());
  schema_version = kHistorySchemaVersion;
  // A wave's checksum changed form up to v4; a v4 wave's stands (it is checked when read), and so
  // does it in v7, whose checksums skip multi-fidelity columns that are all NULL.
  if (from < 4) {
    std::vector<int> waves;
    Statement rows(db, "SELECT wave FROM wave ORDER BY wave");
    while (rows.Step()) waves.push_back(static_cast<int>(rows.Int(0)));
    chain.wave = -1;
    for (int wave : waves) StoreWaveHash(wave);
  }
  StoreRunHashes();
  transaction.Commit();
}

}  // namespace combabc
