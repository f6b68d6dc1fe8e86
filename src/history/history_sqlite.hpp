#pragma once
// Thin RAII wrappers over the SQLite C API for the run history (private to src/history). Every
// failure becomes a one-line combabc::Error naming the history file.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace combabc::history {

class Database;

class Statement {
 public:
  Statement(Database& db, const char* sql);
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&&) = delete;
  Statement(const Statement&) = delete;
  ~Statement();

  // Binds are 1-based, as in SQLite. Empty blobs bind NULL.
  Statement& Bind(int i, std::int64_t value);
  Statement& Bind(int i, int value) { return Bind(i, static_cast<std::int64_t>(value)); }
  Statement& Bind(int i, double value);
  Statement& Bind(int i, const std::string& value);
  Statement& BindBlob(int i, std::span<const std::uint8_t> bytes);
  // A blob even when empty (zero bytes, not NULL): a continuous-only run's particle bits.
  Statement& BindBytes(int i, std::span<const std::uint8_t> bytes);
  Statement& BindNull(int i);

  // True while a row is available; false when done. Resets itself after the last row.
  bool Step();
  // Runs a statement that returns no rows, then resets it for reuse.
  void Run();
  void Reset();

  // Columns are 0-based, as in SQLite. A NULL REAL reads as NaN (SQLite stores NaN as NULL).
  std::int64_t Int(int column) const;
  double Real(int column) const;
  std::string Text(int column) const;
  std::vector<std::uint8_t> Blob(int column) const;
  bool IsNull(int column) const;
  // The column's storage class (SQLITE_INTEGER ... SQLITE_NULL) and its bytes (TEXT or BLOB), as
  // the checksums see them.
  int Type(int column) const;
  std::span<const std::uint8_t> Bytes(int column) const;

 private:
  Database* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

class Database {
 public:
  // Opens `path`; create = may create it. Failure to open is kNoInput (or kCantCreate if create).
  Database(const std::string& path, bool create, bool read_only);
  Database(const Database&) = delete;
  ~Database();

  void Exec(const char* sql);
  // Exec that reports failure instead of throwing.
  bool TryExec(const char* sql);
  std::int64_t QueryInt(const char* sql);
  // Rows changed by the last INSERT / UPDATE / DELETE.
  int Changes();
  // Inside BEGIN ... COMMIT (ours or a caller's).
  bool InTransaction();
  sqlite3* handle() { return db_; }
  const std::string& path() const { return path_; }
  // Throws the Error for SQLite result code `rc` (kData for corrupt / not a database, else kIo).
  [[noreturn]] void Fail(int rc, const std::string& what) const;
  void Close();

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
};

// One transaction; rolls back unless Commit() was called.
class Transaction {
 public:
  explicit Transaction(Database& db);
  Transaction(const Transaction&) = delete;
  ~Transaction();
  void Commit();

 private:
  Database* db_;
  bool done_ = false;
};

// One consistent snapshot for a multi-statement read, so that a reader never mixes two commits
// of a run being written (each wave's checksum must match the rows read with it). A no-op inside
// a transaction already open.
class ReadSnapshot {
 public:
  explicit ReadSnapshot(Database& db);
  ReadSnapshot(const ReadSnapshot&) = delete;
  ~ReadSnapshot();

 private:
  Database* db_ = nullptr;
};

// Vectors as BLOBs: doubles as little-endian IEEE-754 binary64, bits packed 8 per byte with bit k
// in byte k/8 at position k%8 (least significant first) -- numpy: unpackbits(bitorder="little").
std::vector<std::uint8_t> PackDoubles(std::span<const double> values);
std::vector<double> UnpackDoubles(const std::vector<std::uint8_t>& bytes, const std::string& path);
std::vector<std::uint8_t> PackBits(std::span<const std::uint8_t> bits);
std::vector<std::uint8_t> UnpackBits(const std::vector<std::uint8_t>& bytes,
                                     int dimension,
                                     const std::string& path);

// Now as ISO 8601 UTC, e.g. "2026-11-21T06:00:00Z".
std::string UtcNow();

}  // namespace combabc::history
