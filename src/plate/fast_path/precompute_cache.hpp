#pragma once
// The disk cache of a sensor model's precomputed pieces (docs/model.md, "Start-up and the
// precompute cache"). An entry is one file, `<key>.precompute`, in the cache folder:
//   header: magic "CMBCPRE1", format version (u32), 4 zero bytes, key (2 x u64), payload size
//           (u64), payload checksum (XXH3 64-bit, u64)
//   payload: what a ByteWriter wrote
// The key is a 128-bit XXH3 hash of everything the pieces depend on: the build of the plate code,
// the element matrices, the mesh, the supports, the loads, the outputs and the frequency
// (SensorModel::PrecomputeKey). Entries are written to a temporary of their own and renamed into
// place, so readers and writers in other processes only ever see whole entries; a damaged entry
// (size, magic, key or checksum wrong) is never trusted: it is rebuilt and replaced.
// A checksum proves no authorship (anyone can recompute it), so trust comes from the file system
// (docs/model.md, "Who the cache trusts"): the folders are created owner-only (0700); a folder on
// the way that another user could write, or a cache folder not this user's, is not used at all
// (nothing read, written or evicted there; one warning); an entry that is not a regular file of
// this user's, writable by nobody else and no larger than the caller's model can need, is a miss
// (rebuilt and replaced), found so without blocking, following a link or allocating.
#include <array>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>

namespace combabc::plate {

using PrecomputeKey = std::array<std::uint64_t, 2>;

// Incremental XXH3-128 over the key material.
class KeyHasher {
 public:
  KeyHasher();
  ~KeyHasher();
  KeyHasher(const KeyHasher&) = delete;
  KeyHasher& operator=(const KeyHasher&) = delete;
  void Add(const void* data, std::size_t size);
  template <class T>
  void AddValue(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    Add(&value, sizeof(T));
  }
  void AddText(std::string_view text) {
    AddValue(text.size());
    Add(text.data(), text.size());
  }
  template <class Matrix>
  void AddMatrix(const Matrix& m) {
    AddValue(static_cast<std::int64_t>(m.rows()));
    AddValue(static_cast<std::int64_t>(m.cols()));
    Add(m.data(), sizeof(typename Matrix::Scalar) * static_cast<std::size_t>(m.size()));
  }
  PrecomputeKey Finish() const;

 private:
  void* state_;
};

// The payload: fixed-size values in the machine's byte order (the key covers the build, hence the
// architecture), vectors and matrices with their sizes first. Written straight to the entry's file
// through a small buffer (no copy of the payload in memory), its checksum computed on the way.
class ByteWriter {
 public:
  explicit ByteWriter(int fd);
  ~ByteWriter();
  ByteWriter(const ByteWriter&) = delete;
  ByteWriter& operator=(const ByteWriter&) = delete;
  template <class T>
  void Value(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    Put(&value, sizeof(T));
  }
  template <class T>
  void Vector(const std::vector<T>& v) {
    Value(static_cast<std::uint64_t>(v.size()));
    for (const T& x : v) Value(x);
  }
  template <class Matrix>
  void Dense(const Matrix& m) {
    Value(static_cast<std::int64_t>(m.rows()));
    Value(static_cast<std::int64_t>(m.cols()));
    Put(m.data(), sizeof(typename Matrix::Scalar) * static_cast<std::size_t>(m.size()));
  }
  // Writes what is buffered; false if any write failed.
  bool Flush();
  std::uint64_t size() const { return size_; }
  std::uint64_t checksum() const;

 private:
  void Put(const void* data, std::size_t size);
  int fd_;
  bool ok_ = true;
  std::uint64_t size_ = 0;
  std::vector<char> buffer_;
  void* state_;  // XXH3-64 over every byte put
};

// Reads what a ByteWriter wrote, `size` bytes from the entry's file, straight into the values and
// matrices, the checksum computed on the way. A read past the end, a size beyond what is left or
// a failed read sets failed() and yields zeros: the caller then discards all it read.
class ByteReader {
 public:
  ByteReader(int fd, std::uint64_t size);
  ~ByteReader();
  ByteReader(const ByteReader&) = delete;
  ByteReader& operator=(const ByteReader&) = delete;
  template <class T>
  T Value() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value{};
    Get(&value, sizeof(T));
    return value;
  }
  template <class T>
  std::vector<T> Vector() {
    const auto n = Value<std::uint64_t>();
    if (failed_ || n > left_ / sizeof(T)) {
      failed_ = true;
      return {};
    }
    std::vector<T> v(n);
    for (T& x : v) x = Value<T>();
    return v;
  }
  template <class Matrix>
  Matrix Dense() {
    const auto rows = Value<std::int64_t>();
    const auto cols = Value<std::int64_t>();
    using Scalar = typename Matrix::Scalar;
    const std::uint64_t left = left_ / sizeof(Scalar);
    if (failed_ || rows < 0 || cols < 0 || (Matrix::ColsAtCompileTime == 1 && cols != 1) ||
        (cols > 0 && static_cast<std::uint64_t>(rows) > left / static_cast<std::uint64_t>(cols))) {
      failed_ = true;
      return Matrix();
    }
    Matrix m(rows, cols);
    Get(m.data(), sizeof(Scalar) * static_cast<std::size_t>(m.size()));
    return m;
  }
  bool failed() const { return failed_; }
  bool at_end() const { return left_ == 0; }
  std::uint64_t checksum() const;

 private:
  void Get(void* data, std::size_t size);
  int fd_;
  std::uint64_t left_;       // payload bytes not yet handed out
  std::uint64_t file_left_;  // payload bytes not yet read from the file
  bool failed_ = false;
  std::vector<char> buffer_;
  std::size_t buffer_at_ = 0;
  void* state_;  // XXH3-64 over every byte read
};

// The build of the plate code (sources, compiler, flags), set by CMake: an entry written by
// another build is never read.
std::string_view PlateBuildId();

// Why `directory` (which exists) cannot be trusted with cache entries, or "" when it can: it or a
// folder on its way (links resolved) is owned by another user (root may own the folders on the
// way), or is writable by group or others (a folder on the way may be, when sticky, as /tmp).
std::string UntrustedCacheFolder(const std::string& directory);

// Where the one warning per folder and process about an untrusted cache folder goes: stderr
// ("combabc: warning: ...") unless replaced; an empty function silences it.
void SetUntrustedCacheWarning(std::function<void(const std::string&)> sink);

class PrecomputeCache {
 public:
  // An empty `directory` disables the cache (Load finds nothing, Store does nothing).
  PrecomputeCache(std::string directory, std::uint64_t max_bytes);

  // Reads the entry stored under `key` with `read`, which returns whether it made sense of it; true
  // when it did, read the whole payload and the payload's checksum matched (checked after `read`
  // returns: what it built must not be used otherwise). An entry whose payload is larger than
  // `max_payload_bytes` (what the caller's model can need at most) is a miss, found before
  // anything is read. A hit marks the entry as just used (its modification time), for the
  // eviction order.
  bool Load(const PrecomputeKey& key,
            std::uint64_t max_payload_bytes,
            const std::function<bool(ByteReader&)>& read) const;

  // Stores what `write` writes under `key` (replacing a damaged entry), then removes the least
  // recently used entries until the folder's entries fit in max_bytes (never the one just stored).
  // A cache that cannot be written is skipped: it only saves time. Returns whether it was stored.
  bool Store(const PrecomputeKey& key, const std::function<void(ByteWriter&)>& write) const;

  // The entry's file name for `key` (32 hex digits + ".precompute").
  static std::string FileName(const PrecomputeKey& key);

 private:
  std::string directory_;
  std::uint64_t max_bytes_;
};

}  // namespace combabc::plate
