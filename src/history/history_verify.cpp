// Checking a run history: SQLite's own structure checks, the metadata's shape and checksums (on
// every open), and `combabc verify`'s full pass over every wave.
#include <sqlite3.h>

#include <limits>
#include <set>
#include <string>
#include <tuple>

#include "combabc/core/error.hpp"
#include "history/history_impl.hpp"

namespace combabc {
namespace {

using history::Statement;

[[noreturn]] void Corrupt(const std::string& path,
                          const std::string& field,
                          const std::string& what) {
  throw Error(ErrorKind::kData, "corrupt run history: " + what, path, 0, field);
}

// A checksum row of `meta` against the value recomputed now.
void CheckDigest(history::Database& db, const char* key, std::uint64_t computed, const char* what) {
  Statement stored(db, "SELECT value FROM meta WHERE key = ?1");
  stored.Bind(1, std::string(key));
  std::optional<std::uint64_t> digest;
  if (stored.Step()) {
    digest = history::ParseHexDigest(stored.Text(0));
    stored.Reset();
  }
  if (!digest) {
    Corrupt(db.path(), std::string("meta.") + key, "the checksum is missing or malformed");
  }
  if (*digest != computed) {
    Corrupt(
        db.path(), std::string("meta.") + key, std::string(what) + " do not match their checksum");
  }
}

// Rows numbered 0, 1, 2, ... in `sql` (first column); returns how many.
std::size_t CountNumberedRows(history::Database& db, const char* sql, const char* table) {
  Statement rows(db, sql);
  std::int64_t expected = 0;
  while (rows.Step()) {
    if (rows.Type(0) != SQLITE_INTEGER || rows.Int(0) != expected) {
      rows.Reset();
      Corrupt(db.path(),
              table,
              "rows are not numbered 0, 1, 2, ... (row " + std::to_string(expected) + ")");
    }
    ++expected;
  }
  return static_cast<std::size_t>(expected);
}

// A schema object as sqlite_master lists it: type, name, and the table it belongs to.
using SchemaObject = std::tuple<std::string, std::string, std::string>;

// What the schema of `version` creates (history_create.cpp): its tables and the indexes SQLite
// makes for their non-integer primary keys. No trigger and no view, ever.
std::set<SchemaObject> ExpectedObjects(int version) {
  std::set<SchemaObject> objects;
  auto table = [&](const char* name) { objects.emplace("table", name, name); };
  auto key_index = [&](const char* table_name) {
    objects.emplace(
        "index", std::string("sqlite_autoindex_") + table_name + "_1", std::string(table_name));
  };
  for (const char* name :
       {"meta", "run", "bit", "component", "output_position", "measured", "wave", "particle"}) {
    table(name);
  }
  key_index("meta");
  key_index("particle");
  if (version >= 3) {
    table("real");
    table("proposal");
  }
  if (version >= 4) {
    table("failure");
    key_index("failure");
  }
  if (version >= 6) table("experiment");  // INTEGER PRIMARY KEY: no index of its own
  return objects;
}

// The statistics tables ANALYZE (or PRAGMA optimize) makes: SQLite's own, harmless to combabc.
bool IsSqliteStatistics(const SchemaObject& object) {
  const std::string& name = std::get<1>(object);
  return std::get<0>(object) == "table" && name.rfind("sqlite_stat", 0) == 0;
}

// Whether `table` has a row of a wave not in 0 .. waves-1. Walks the distinct values of its
// leading (wave, candidate) key through the index, one seek each: at most waves + 1 seeks.
// Returns the first such value as text, or nullopt.
std::optional<std::string> OrphanWave(history::Database& db,
                                      const char* table,
                                      std::int64_t waves) {
  Statement first(db,
                  (std::string("SELECT wave FROM ") + table + " ORDER BY wave LIMIT 1").c_str());
  Statement next(
      db,
      (std::string("SELECT wave FROM ") + table + " WHERE wave > ?1 ORDER BY wave LIMIT 1")
          .c_str());
  Statement* row = &first;
  while (row->Step()) {
    if (row->Type(0) != SQLITE_INTEGER || row->Int(0) < 0 || row->Int(0) >= waves) {
      std::string value = row->Text(0);
      row->Reset();
      return value;
    }
    const std::int64_t wave = row->Int(0);
    row->Reset();
    next.Bind(1, wave);
    row = &next;
  }
  return std::nullopt;
}

}  // namespace

void HistoryStore::Impl::CheckSchemaObjects() {
  std::set<SchemaObject> expected = ExpectedObjects(schema_version);
  Statement objects(db, "SELECT type, name, tbl_name FROM sqlite_master ORDER BY type, name");
  while (objects.Step()) {
    SchemaObject object{objects.Text(0), objects.Text(1), objects.Text(2)};
    if (expected.erase(object) != 0 || IsSqliteStatistics(object)) continue;
    objects.Reset();
    const auto& [type, name, table] = object;
    std::string what = "has a " + type + " that combabc did not create";
    if (!table.empty() && table != name) what.append(" (on table ").append(table).append(")");
    what += "; combabc does not read or write a history that SQL outside it could change";
    std::string field = type;
    field.append(" ").append(name);
    Corrupt(db.path(), field, what);
  }
  if (!expected.empty()) {
    const auto& [type, name, table] = *expected.begin();
    Corrupt(db.path(), type + " " + name, "the " + type + " is missing");
  }
}

void HistoryStore::Impl::CheckWaveSet(bool full) {
  const std::string& path = db.path();
  Statement rows(db, "SELECT count(*), min(wave), max(wave) FROM wave");
  rows.Step();
  const std::int64_t waves = rows.Int(0);
  const std::int64_t first = rows.Int(1);
  const std::int64_t last = rows.Int(2);
  rows.Reset();
  if (waves > 0 && (first != 0 || last != waves - 1)) {
    // 1-based as the user counts waves; a number written by hand may be INT64_MAX.
    const auto one_based = [](std::int64_t wave) {
      return wave < std::numeric_limits<std::int64_t>::max() ? std::to_string(wave + 1)
                                                             : std::to_string(wave) + " + 1";
    };
    Corrupt(path,
            "wave",
            "waves are not numbered 1, 2, 3, ... (" + std::to_string(waves) + " rows, from wave " +
                one_based(first) + " to " + one_based(last) + ")");
  }
  if (has_wave_count()) {
    Statement count(db, "SELECT value FROM meta WHERE key = 'wave_count'");
    std::optional<std::int64_t> recorded;
    if (count.Step()) {
      const std::string text = count.Text(0);
      count.Reset();
      if (!text.empty() && text.size() < 12 &&
          text.find_first_not_of("0123456789") == std::string::npos) {
        recorded = std::stoll(text);
      }
    }
    if (!recorded) Corrupt(path, "meta.wave_count", "the wave count is missing or malformed");
    if (*recorded != waves) {
      Corrupt(path,
              "meta.wave_count",
              "the run recorded " + std::to_string(*recorded) + " waves, the file holds " +
                  std::to_string(waves) + " (waves deleted or added outside combabc)");
    }
  }
  Statement summary(db, "SELECT waves_completed FROM run WHERE id = 1");
  if (summary.Step() && !summary.IsNull(0)) {
    const std::int64_t completed = summary.Int(0);
    summary.Reset();
    const std::int64_t complete =
        db.QueryInt("SELECT count(*) FROM wave WHERE ended != 0 AND complete != 0");
    // Fewer: waves deleted. (More is no loss: Finish records the summary it is given, which a
    // caller of the library may have left at 0.)
    if (complete < completed) {
      Corrupt(path,
              "run.waves_completed",
              "the run ended with " + std::to_string(completed) +
                  " complete waves, the file holds only " + std::to_string(complete) +
                  " (waves deleted outside combabc)");
    }
  }
  std::vector<const char*> tables = {"particle"};
  if (has_failures()) tables.push_back("failure");
  for (const char* table : tables) {
    std::optional<std::string> orphan = OrphanWave(db, table, waves);
    if (!orphan && full) {
      // Values between two whole numbers (1.5) sort between them: the walk above passes them.
      Statement odd(db,
                    (std::string("SELECT wave FROM ") + table +
                     " WHERE wave NOT IN (SELECT wave FROM wave) LIMIT 1")
                        .c_str());
      if (odd.Step()) orphan = odd.Text(0);
    }
    if (orphan) {
      Corrupt(path,
              table,
              std::string("has rows of wave '") + *orphan +
                  "', which has no wave row (orphans: waves deleted outside combabc)");
    }
  }
}

std::vector<std::string> HistoryStore::Impl::StorageProblems(bool full) {
  std::vector<std::string> problems;
  try {
    Statement check(db, full ? "PRAGMA integrity_check(100)" : "PRAGMA quick_check(1)");
    while (check.Step()) {
      std::string line = check.Text(0);
      if (line == "ok") continue;
      // SQLite's report may span lines ("*** in database main ***\n..."): one line each here.
      const std::string banner = "*** in database main ***";
      if (line.rfind(banner, 0) == 0) line.erase(0, banner.size());
      for (char& c : line) {
        if (c == '\n' || c == '\r') c = ' ';
      }
      problems.push_back(line.substr(
          line.find_first_not_of(' ') == std::string::npos ? 0 : line.find_first_not_of(' ')));
    }
  } catch (const Error& error) {
    problems.push_back(error.message());
  }
  return problems;
}

void HistoryStore::Impl::CheckMetadata() {
  const std::string& path = db.path();
  if (checksummed()) {
    CheckDigest(db,
                "metadata_hash",
                history::MetadataHash(db, schema_version),
                "the run's configuration, problem description and measured data");
  }
  Statement run(db, "SELECT dimension FROM run WHERE id = 1");
  if (!run.Step()) Corrupt(path, "run", "no run row");
  const std::int64_t dimension = run.Int(0);
  run.Reset();
  // 0 bits is a continuous-only run (its reals are checked with the run's parameters).
  if (dimension < 0 || dimension > 1'000'000) {
    Corrupt(path, "run.dimension", "is " + std::to_string(dimension) + ", not a number of bits");
  }
  shape.dimension = static_cast<int>(dimension);
  if (CountNumberedRows(db, "SELECT bit FROM bit ORDER BY bit", "bit") !=
      static_cast<std::size_t>(dimension)) {
    Corrupt(
        path, "bit", "the table does not have one row per bit (" + std::to_string(dimension) + ")");
  }
  shape.components =
      CountNumberedRows(db, "SELECT component FROM component ORDER BY component", "component");
  shape.threshold_components = 0;
  Statement kinds(db, "SELECT kind FROM component ORDER BY component");
  while (kinds.Step()) {
    const std::string kind = kinds.Text(0);
    // A likelihood component has a schedule slot (its temperature) like a threshold.
    if (kind == "threshold" || kind == "neg_log_likelihood") {
      ++shape.threshold_components;
    } else if (kind != "indicator") {
      kinds.Reset();
      Corrupt(path, "component.kind", "unknown kind '" + kind + "'");
    }
  }
  shape.outputs =
      CountNumberedRows(db, "SELECT i FROM output_position ORDER BY i", "output_position");
  const std::size_t measured =
      CountNumberedRows(db, "SELECT i FROM measured ORDER BY i", "measured");
  if (has_experiments()) CheckExperiments(measured);
  shape.reals = 0;
  if (!has_reals()) return;
  shape.reals = CountNumberedRows(db, "SELECT i FROM real ORDER BY i", "real");
  Statement reals(db, "SELECT i, name, kind FROM real ORDER BY i");
  while (reals.Step()) {
    const std::string field = "real " + std::to_string(reals.Int(0) + 1);
    const std::string kind = reals.Text(2);
    if (reals.Text(1).empty() || !ParseEnum<PriorKind>(kind)) {
      reals.Reset();
      Corrupt(path, field, "has no name or an unknown prior kind '" + kind + "'");
    }
  }
  Statement proposal(db, "SELECT binary_kernel, continuous_kernel FROM proposal WHERE id = 1");
  if (!proposal.Step()) Corrupt(path, "proposal", "no proposal row");
  const std::string binary = proposal.Text(0);
  const std::string continuous = proposal.Text(1);
  proposal.Reset();
  if (!ParseEnum<BinaryKernelKind>(binary)) {
    Corrupt(path, "proposal.binary_kernel", "unknown kernel '" + binary + "'");
  }
  if (!ParseEnum<ContinuousKernelKind>(continuous)) {
    Corrupt(path, "proposal.continuous_kernel", "unknown kernel '" + continuous + "'");
  }
}

void HistoryStore::Impl::CheckExperiments(std::size_t measured) {
  const std::string& path = db.path();
  const std::size_t count =
      CountNumberedRows(db, "SELECT e FROM experiment ORDER BY e", "experiment");
  if (count == 0) Corrupt(path, "experiment", "the table is empty (a run has an experiment)");
  // Each count is an integer no larger than the run's total, so that the sums cannot overflow.
  const std::size_t totals[] = {shape.outputs, measured, shape.components};
  const char* const columns[] = {"outputs", "measured", "components"};
  std::size_t sums[] = {0, 0, 0};
  std::set<std::string> names;
  Statement rows(db, "SELECT e, name, outputs, measured, components FROM experiment ORDER BY e");
  while (rows.Step()) {
    const std::string which = "experiment " + std::to_string(rows.Int(0) + 1);
    if (rows.Type(1) != SQLITE_TEXT || !names.insert(rows.Text(1)).second) {
      const std::string name = rows.Text(1);
      rows.Reset();
      Corrupt(path, which + ", name", "'" + name + "' is not text or repeats an earlier name");
    }
    for (int c = 0; c < 3; ++c) {
      const int column = 2 + c;
      const bool integer = rows.Type(column) == SQLITE_INTEGER;
      const std::int64_t value = integer ? rows.Int(column) : -1;
      if (value < 0 || static_cast<std::uint64_t>(value) > totals[c]) {
        const std::string text = rows.Text(column);
        rows.Reset();
        Corrupt(path,
                which + ", " + columns[c],
                "is '" + text + "', not a count from 0 to " + std::to_string(totals[c]));
      }
      sums[c] += static_cast<std::size_t>(value);
    }
  }
  const char* const what[] = {"output positions", "measured points", "distance components"};
  for (int c = 0; c < 3; ++c) {
    if (sums[c] != totals[c]) {
      Corrupt(path,
              std::string("experiment.") + columns[c],
              "the experiments hold " + std::to_string(sums[c]) + " " + what[c] + ", the run has " +
                  std::to_string(totals[c]));
    }
  }
}

void HistoryStore::Impl::CheckRunState() {
  if (checksummed()) {
    CheckDigest(db,
                "run_state_hash",
                history::RunStateHash(db, schema_version),
                "the run's status and summary");
  }
}

HistoryCheck HistoryStore::Verify(const std::string& path) {
  // Opened as report and export open it, minus the checks that stop at the first problem.
  HistoryStore store = OpenFile(path, /*read_only=*/true, /*check=*/false);
  Impl& impl = *store.impl_;
  HistoryCheck result;
  result.checksummed = impl.checksummed();
  result.schema_version = impl.schema_version;
  auto collect = [&](auto&& check) {
    try {
      check();
    } catch (const Error& error) {
      result.problems.push_back(error.what());
    }
  };
  for (const std::string& line : impl.StorageProblems(/*full=*/true)) {
    result.problems.push_back(path);
    result.problems.back() += ": SQLite integrity_check: ";
    result.problems.back() += line;
  }
  history::ReadSnapshot snapshot(impl.db);
  collect([&] { impl.CheckSchemaObjects(); });
  bool metadata_ok = false;
  collect([&] {
    impl.CheckMetadata();
    metadata_ok = true;
  });
  collect([&] { impl.CheckRunState(); });
  collect([&] { impl.CheckWaveSet(/*full=*/true); });
  collect([&] { store.LoadMetadata(); });
  if (!metadata_ok) return result;  // the waves cannot be checked without the run's shape
  collect([&] {
    Statement rows(impl.db, (impl.WaveSelect() + " ORDER BY wave").c_str());
    int position = 0;
    while (rows.Step()) {
      collect([&] { impl.ReadWave(rows, position); });
      ++position;
      ++result.waves;
    }
  });
  return result;
}

}  // namespace combabc
