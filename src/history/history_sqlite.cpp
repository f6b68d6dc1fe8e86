#include "history/history_sqlite.hpp"

#include <sqlite3.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>

#include "combabc/core/error.hpp"

namespace combabc::history {
namespace {

// The BLOB layout is little-endian by definition; a big-endian port would byte-swap here.
static_assert(std::endian::native == std::endian::little,
              "history BLOBs are little-endian; add byte swapping for this platform");

// SQLite messages are one line already; this guards the one-line what() contract anyway.
std::string OneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

// The path SQLite is given. SQLite resolves `..` itself and refuses one that climbs above `/`
// ("/../x.sqlite", or a relative chain longer than the working directory is deep), which the
// kernel, and so every other part of combabc, reads as `/`: such a path is resolved here as the
// kernel would (symbolic links of its existing part followed), so that both name the same file.
std::string SqlitePath(const std::string& path) {
  const std::filesystem::path given(path);
  bool climbs = false;
  for (const auto& element : given) climbs = climbs || element == "..";
  if (!climbs) return path;
  std::error_code ec;
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(given, ec);
  return ec || resolved.empty() ? path : resolved.string();
}

}  // namespace

Database::Database(const std::string& path, bool create, bool read_only) : path_(path) {
  int flags = read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE;
  if (create) flags |= SQLITE_OPEN_CREATE;
  const int rc = sqlite3_open_v2(SqlitePath(path).c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = db_ != nullptr ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error(create ? ErrorKind::kCantCreate : ErrorKind::kNoInput,
                "cannot open run history: " + OneLine(message),
                path);
  }
  sqlite3_extended_result_codes(db_, 0);
  // A writer briefly holds the lock while a report reads the same file mid-run.
  sqlite3_busy_timeout(db_, 5000);
}

Database::~Database() { Close(); }

void Database::Close() {
  if (db_ != nullptr) {
    sqlite3_close_v2(db_);  // closes for good once the last statement is finalised
    db_ = nullptr;
  }
}

void Database::Fail(int rc, const std::string& what) const {
  const int primary = rc & 0xff;
  const ErrorKind kind =
      (primary == SQLITE_CORRUPT || primary == SQLITE_NOTADB) ? ErrorKind::kData : ErrorKind::kIo;
  std::string detail = db_ != nullptr ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
  if (primary == SQLITE_NOTADB) detail = "not a combabc run history (" + detail + ")";
  throw Error(kind, OneLine(what + ": " + detail), path_);
}

void Database::Exec(const char* sql) {
  char* message = nullptr;
  const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &message);
  if (rc != SQLITE_OK) {
    sqlite3_free(message);
    Fail(rc, "cannot update run history");
  }
}

bool Database::TryExec(const char* sql) {
  return sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) == SQLITE_OK;
}

std::int64_t Database::QueryInt(const char* sql) {
  Statement statement(*this, sql);
  std::int64_t value = 0;
  if (statement.Step()) {
    value = statement.Int(0);
    statement.Reset();
  }
  return value;
}

int Database::Changes() { return sqlite3_changes(db_); }

bool Database::InTransaction() { return sqlite3_get_autocommit(db_) == 0; }

Statement::Statement(Database& db, const char* sql) : db_(&db) {
  const int rc = sqlite3_prepare_v2(db.handle(), sql, -1, &stmt_, nullptr);
  if (rc != SQLITE_OK) db.Fail(rc, "cannot read run history");
}

Statement::Statement(Statement&& other) noexcept : db_(other.db_), stmt_(other.stmt_) {
  other.stmt_ = nullptr;
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement& Statement::Bind(int i, std::int64_t value) {
  sqlite3_bind_int64(stmt_, i, value);
  return *this;
}

Statement& Statement::Bind(int i, double value) {
  sqlite3_bind_double(stmt_, i, value);
  return *this;
}

Statement& Statement::Bind(int i, const std::string& value) {
  sqlite3_bind_text(stmt_, i, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::BindBlob(int i, std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) return BindNull(i);
  sqlite3_bind_blob(stmt_, i, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
  return *this;
}

Statement& Statement::BindBytes(int i, std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) {
    sqlite3_bind_zeroblob(stmt_, i, 0);
    return *this;
  }
  return BindBlob(i, bytes);
}

Statement& Statement::BindNull(int i) {
  sqlite3_bind_null(stmt_, i);
  return *this;
}

bool Statement::Step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) {
    Reset();
    return false;
  }
  sqlite3_reset(stmt_);
  db_->Fail(rc, "run history access failed");
}

void Statement::Run() {
  while (Step()) {
  }
  sqlite3_clear_bindings(stmt_);
}

void Statement::Reset() { sqlite3_reset(stmt_); }

std::int64_t Statement::Int(int column) const { return sqlite3_column_int64(stmt_, column); }

double Statement::Real(int column) const {
  if (sqlite3_column_type(stmt_, column) == SQLITE_NULL) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return sqlite3_column_double(stmt_, column);
}

std::string Statement::Text(int column) const {
  const unsigned char* text = sqlite3_column_text(stmt_, column);
  if (text == nullptr) return {};
  return std::string(reinterpret_cast<const char*>(text),
                     static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)));
}

std::vector<std::uint8_t> Statement::Blob(int column) const {
  const void* data = sqlite3_column_blob(stmt_, column);
  const int size = sqlite3_column_bytes(stmt_, column);
  if (data == nullptr || size <= 0) return {};
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  return std::vector<std::uint8_t>(bytes, bytes + size);
}

bool Statement::IsNull(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

int Statement::Type(int column) const { return sqlite3_column_type(stmt_, column); }

std::span<const std::uint8_t> Statement::Bytes(int column) const {
  const void* data = Type(column) == SQLITE_TEXT
                         ? static_cast<const void*>(sqlite3_column_text(stmt_, column))
                         : sqlite3_column_blob(stmt_, column);
  const int size = sqlite3_column_bytes(stmt_, column);
  if (data == nullptr || size <= 0) return {};
  return {static_cast<const std::uint8_t*>(data), static_cast<std::size_t>(size)};
}

Transaction::Transaction(Database& db) : db_(&db) {
  // IMMEDIATE takes the write lock up front, so a concurrent reader cannot make COMMIT fail.
  db.Exec("BEGIN IMMEDIATE");
}

Transaction::~Transaction() {
  if (!done_) sqlite3_exec(db_->handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::Commit() {
  db_->Exec("COMMIT");
  done_ = true;
}

ReadSnapshot::ReadSnapshot(Database& db) {
  if (db.InTransaction()) return;
  db.Exec("BEGIN");
  db_ = &db;
}

ReadSnapshot::~ReadSnapshot() {
  if (db_ != nullptr) sqlite3_exec(db_->handle(), "COMMIT", nullptr, nullptr, nullptr);
}

std::vector<std::uint8_t> PackDoubles(std::span<const double> values) {
  std::vector<std::uint8_t> bytes(values.size() * sizeof(double));
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

std::vector<double> UnpackDoubles(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  if (bytes.size() % sizeof(double) != 0) {
    throw Error(
        ErrorKind::kData, "corrupt run history: a vector of doubles has a stray byte", path);
  }
  std::vector<double> values(bytes.size() / sizeof(double));
  if (!values.empty()) std::memcpy(values.data(), bytes.data(), bytes.size());
  return values;
}

std::vector<std::uint8_t> PackBits(std::span<const std::uint8_t> bits) {
  std::vector<std::uint8_t> bytes((bits.size() + 7) / 8, 0);
  for (std::size_t k = 0; k < bits.size(); ++k) {
    if (bits[k] != 0) bytes[k / 8] = static_cast<std::uint8_t>(bytes[k / 8] | (1u << (k % 8)));
  }
  return bytes;
}

std::vector<std::uint8_t> UnpackBits(const std::vector<std::uint8_t>& bytes,
                                     int dimension,
                                     const std::string& path) {
  const auto d = static_cast<std::size_t>(dimension);
  if (bytes.size() != (d + 7) / 8) {
    throw Error(ErrorKind::kData,
                "corrupt run history: a particle's bits do not match dimension " +
                    std::to_string(dimension),
                path);
  }
  std::vector<std::uint8_t> bits(d);
  for (std::size_t k = 0; k < d; ++k) {
    bits[k] = static_cast<std::uint8_t>((bytes[k / 8] >> (k % 8)) & 1u);
  }
  return bits;
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

}  // namespace combabc::history
