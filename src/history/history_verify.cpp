// Checking a run history: SQLite's own structure checks, the metadata's shape and checksums (on
// every open), and `combabc verify`'s full pass over every wave.
#include <sqlite3.h>

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

}  // namespace

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
  if (dimension < 1 || dimension > 1'000'000) {
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
  CountNumberedRows(db, "SELECT i FROM measured ORDER BY i", "measured");
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

void HistoryStore::Impl::CheckRunState() {
  if (checksummed()) {
    CheckDigest(db, "run_state_hash", history::RunStateHash(db), "the run's status and summary");
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
  bool metadata_ok = false;
  collect([&] {
    impl.CheckMetadata();
    metadata_ok = true;
  });
  collect([&] { impl.CheckRunState(); });
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
