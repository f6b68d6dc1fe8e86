// libFuzzer target, structure-aware: the run-history reader on a *valid* history whose values the
// input changes. At start-up the library writes a tiny history (history_seed.hpp) and its schema
// is read back (tables, columns); each input is then decoded by FuzzedDataProvider into up to 32
// SQL edits of a fresh copy -- set a cell (one row or all) to a chosen value, copy a row with one
// cell changed, delete a row, change PRAGMA user_version -- and the result is read back in full
// like history_fuzzer does. Values favour the edges: NULL, 0 / -1 / INT64_MIN, NaN / inf,
// status and estimator words, and BLOBs of doubles of the wrong length. This reaches the history
// readers' own checks (dimensions, blob lengths, missing rows, wave order) that byte mutations of
// the file seldom get past SQLite to. A combabc::Error is the expected outcome; anything else is
// a finding (see fuzz_util.hpp).
#include <fuzzer/FuzzedDataProvider.h>
#include <sqlite3.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <system_error>
#include <vector>

#include "combabc/core/error.hpp"
#include "fuzz_util.hpp"
#include "history_readers.hpp"
#include "history_seed.hpp"

namespace {

// COMBABC_FUZZ_VERBOSE=1: print each edit (SQL with its values) and copy the edited history to
// ./history_patch_last.sqlite before reading it, to see what an input does (docs/fuzzing.md).
bool Verbose() {
  static const bool verbose = std::getenv("COMBABC_FUZZ_VERBOSE") != nullptr;
  return verbose;
}

struct Table {
  std::string name;
  std::vector<std::string> columns;
};

struct Template {
  std::vector<std::uint8_t> bytes;
  std::vector<Table> tables;
};

[[noreturn]] void Die(const std::string& what) {
  std::fprintf(stderr, "history_patch_fuzzer: %s\n", what.c_str());
  std::abort();
}

std::vector<std::string> Column0(sqlite3* db, const std::string& sql, int column) {
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) Die(sqlite3_errmsg(db));
  std::vector<std::string> values;
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    values.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(stmt, column)));
  }
  sqlite3_finalize(stmt);
  return values;
}

const Template& GetTemplate() {
  static const Template t = [] {
    Template made;
    const std::string path = combabc::fuzz::ScratchDir() + "/template.sqlite";
    try {
      combabc::fuzz::WriteSeedHistory(path);
    } catch (const combabc::Error& error) {
      Die(std::string("cannot write the template history: ") + error.what());
    }
    std::ifstream in(path, std::ios::binary);
    made.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      Die("cannot open the template history");
    }
    for (const std::string& name :
         Column0(db, "SELECT name FROM sqlite_schema WHERE type = 'table' ORDER BY name", 0)) {
      made.tables.push_back({name, Column0(db, "PRAGMA table_info(\"" + name + "\")", 1)});
    }
    sqlite3_close(db);
    if (made.bytes.empty() || made.tables.empty()) Die("empty template history");
    return made;
  }();
  return t;
}

constexpr std::int64_t kInts[] = {0,
                                  1,
                                  -1,
                                  2,
                                  3,
                                  4,
                                  6,
                                  7,
                                  8,
                                  100,
                                  std::numeric_limits<std::int32_t>::max(),
                                  std::numeric_limits<std::int32_t>::min(),
                                  std::int64_t{1} << 31,
                                  (std::int64_t{1} << 32) + 1,
                                  std::numeric_limits<std::int64_t>::max(),
                                  std::numeric_limits<std::int64_t>::min()};
constexpr double kDoubles[] = {0.0,
                               -0.0,
                               1.0,
                               -1.0,
                               0.5,
                               1e-320,
                               1e308,
                               -1e308,
                               2147483648.0,
                               9.3e18,
                               std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity(),
                               std::numeric_limits<double>::quiet_NaN()};
const char* const kWords[] = {"running",
                              "finished",
                              "failed",
                              "interrupted",
                              "paper",
                              "importance",
                              "threshold",
                              "indicator",
                              "max_waves",
                              "target_reached",
                              "interrupted",
                              "",
                              "m",
                              "cm",
                              "18446744073709551615",
                              "-1",
                              "1e999",
                              "independent",
                              "logistic",
                              "normal",
                              "olcm",
                              "uniform",
                              "truncated_normal",
                              "geometric",
                              "mixture"};

double ConsumeDouble(FuzzedDataProvider& in) {
  return in.ConsumeBool() ? in.PickValueInArray(kDoubles) : in.ConsumeFloatingPoint<double>();
}

// Binds parameter 1 to a value the input chooses.
void BindValue(FuzzedDataProvider& in, sqlite3_stmt* stmt) {
  switch (in.ConsumeIntegralInRange(0, 8)) {
    case 0:
      sqlite3_bind_null(stmt, 1);
      break;
    case 1:
      sqlite3_bind_int64(stmt, 1, in.PickValueInArray(kInts));
      break;
    case 2:
      sqlite3_bind_int64(stmt, 1, in.ConsumeIntegral<std::int64_t>());
      break;
    case 3:
      sqlite3_bind_double(stmt, 1, ConsumeDouble(in));
      break;
    case 4:
      sqlite3_bind_text(stmt, 1, in.PickValueInArray(kWords), -1, SQLITE_TRANSIENT);
      break;
    case 5: {
      const std::string text = in.ConsumeRandomLengthString(40);
      sqlite3_bind_text(stmt, 1, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT);
      break;
    }
    case 6: {
      const std::string bytes = in.ConsumeRandomLengthString(80);
      sqlite3_bind_blob(stmt, 1, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
      break;
    }
    default: {  // a vector of doubles, as the history stores them, of a chosen length
      std::vector<double> values(in.ConsumeIntegralInRange<std::size_t>(0, 12));
      for (double& v : values) v = ConsumeDouble(in);
      sqlite3_bind_blob(stmt,
                        1,
                        values.data(),
                        static_cast<int>(values.size() * sizeof(double)),
                        SQLITE_TRANSIENT);
      break;
    }
  }
}

// One edit; SQL errors (a NOT NULL or CHECK constraint, a duplicate key) just leave the file as is.
void Edit(FuzzedDataProvider& in, sqlite3* db, const Template& t) {
  const Table& table = t.tables[in.ConsumeIntegralInRange<std::size_t>(0, t.tables.size() - 1)];
  const std::size_t column_index =
      in.ConsumeIntegralInRange<std::size_t>(0, table.columns.size() - 1);
  const std::string name = "\"" + table.name + "\"";
  const std::string column = "\"" + table.columns[column_index] + "\"";
  const std::string nth =
      "(SELECT rowid FROM " + name + " ORDER BY rowid LIMIT 1 OFFSET ?2)";  // the row to edit
  std::string sql;
  bool has_value = true;
  switch (in.ConsumeIntegralInRange(0, 9)) {
    case 0:
    case 1:
    case 2:
    case 3:
      sql = "UPDATE " + name + " SET " + column + " = ?1 WHERE rowid = " + nth;
      break;
    case 4:
      sql = "UPDATE " + name + " SET " + column + " = ?1";
      break;
    case 5:
    case 6: {  // a copy of a row with one cell changed (a new row when that cell is the key)
      std::string select;
      for (std::size_t c = 0; c < table.columns.size(); ++c) {
        select += (c == 0 ? "" : ", ");
        select += c == column_index ? "?1" : "\"" + table.columns[c] + "\"";
      }
      sql = "INSERT OR REPLACE INTO " + name + " SELECT " + select + " FROM " + name +
            " ORDER BY rowid LIMIT 1 OFFSET ?2";
      break;
    }
    case 7:
    case 8:
      sql = "DELETE FROM " + name + " WHERE rowid = " + nth;
      has_value = false;
      break;
    default:
      sql = "PRAGMA user_version = " + std::to_string(in.PickValueInArray(kInts));
      has_value = false;
      break;
  }
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) {
    sqlite3_finalize(stmt);
    return;
  }
  if (has_value) BindValue(in, stmt);
  if (sqlite3_bind_parameter_count(stmt) >= 2) {
    sqlite3_bind_int(stmt, 2, in.ConsumeIntegralInRange(0, 7));
  }
  const int rc = sqlite3_step(stmt);
  if (Verbose()) {
    char* expanded = sqlite3_expanded_sql(stmt);
    std::fprintf(stderr,
                 "history_patch_fuzzer: %s -> %s\n",
                 expanded != nullptr ? expanded : sql.c_str(),
                 rc == SQLITE_DONE ? "done" : sqlite3_errmsg(db));
    sqlite3_free(expanded);
  }
  sqlite3_finalize(stmt);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  GetTemplate();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Template& t = GetTemplate();
  static const std::string path = combabc::fuzz::ScratchDir() + "/RUN.sqlite";
  combabc::fuzz::RemoveDatabase(path);
  combabc::fuzz::WriteFile(path, t.bytes.data(), t.bytes.size());

  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    Die("cannot open the copy of the template");
  }
  sqlite3_exec(db,
               "PRAGMA journal_mode = MEMORY; PRAGMA synchronous = OFF; BEGIN",
               nullptr,
               nullptr,
               nullptr);
  FuzzedDataProvider in(data, size);
  for (int edits = 0; edits < 32 && in.remaining_bytes() > 0; ++edits) Edit(in, db, t);
  sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  if (Verbose()) {
    std::error_code ignored;
    std::filesystem::copy_file(path,
                               "history_patch_last.sqlite",
                               std::filesystem::copy_options::overwrite_existing,
                               ignored);
  }

  combabc::fuzz::ReadHistory(path);
  return 0;
}
