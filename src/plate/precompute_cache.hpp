#pragma once
// The disk cache of a sensor model's precomputed pieces (docs/model.md, "Start-up and the
// precompute cache"). An entry is one file, `<key>.precompute`, in the cache folder:
//   header: magic "CMBCPRE1", format version (u32), key (2 x u64), payload size (u64),
//           payload checksum (XXH3 64-bit, u64)
//   payload: the bytes a ByteWriter wrote
// The key is a 128-bit XXH3 hash of everything the pieces depend on: the build of the plate code,
// the element matrices, the mesh, the supports, the loads, the outputs and the frequency
// (SensorModel::PrecomputeKey). Entries are written to a temporary of their own and renamed into
// place, so readers and writers in other processes only ever see whole entries; a damaged entry
// (size, magic, key or checksum wrong) is never trusted: it is rebuilt and replaced.
#include <array>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
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
// architecture), vectors and matrices with their sizes first.
class ByteWriter {
 public:
  template <class T>
  void Value(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
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
    const auto* p = reinterpret_cast<const char*>(m.data());
    bytes_.insert(bytes_.end(), p, p + sizeof(typename Matrix::Scalar) * m.size());
  }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
};

// Reads what a ByteWriter wrote. Any read past the end or any size beyond what is left sets
// failed() and yields zeros: the caller then discards the whole entry.
class ByteReader {
 public:
  explicit ByteReader(std::span<const char> bytes) : bytes_(bytes) {}
  template <class T>
  T Value() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value{};
    if (!Take(sizeof(T))) return value;
    std::memcpy(&value, bytes_.data() + at_ - sizeof(T), sizeof(T));
    return value;
  }
  template <class T>
  std::vector<T> Vector() {
    const auto n = Value<std::uint64_t>();
    if (failed_ || n > (bytes_.size() - at_) / sizeof(T)) {
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
    const std::size_t left = (bytes_.size() - at_) / sizeof(Scalar);
    if (failed_ || rows < 0 || cols < 0 || (Matrix::ColsAtCompileTime == 1 && cols != 1) ||
        (cols > 0 && static_cast<std::uint64_t>(rows) > left / static_cast<std::uint64_t>(cols))) {
      failed_ = true;
      return Matrix();
    }
    Matrix m(rows, cols);
    const std::size_t size = sizeof(Scalar) * static_cast<std::size_t>(m.size());
    if (Take(size)) std::memcpy(m.data(), bytes_.data() + at_ - size, size);
    return m;
  }
  bool failed() const { return failed_; }
  bool at_end() const { return at_ == bytes_.size(); }

 private:
  bool Take(std::size_t size) {
    if (failed_ || size > bytes_.size() - at_) {
      failed_ = true;
      return false;
    }
    at_ += size;
    return true;
  }
  std::span<const char> bytes_;
  std::size_t at_ = 0;
  bool failed_ = false;
};

// The build of the plate code (sources, compiler, flags), set by CMake: an entry written by
// another build is never read.
std::string_view PlateBuildId();

class PrecomputeCache {
 public:
  // An empty `directory` disables the cache (Load finds nothing, Store does nothing).
  PrecomputeCache(std::string directory, std::uint64_t max_bytes);

  // The payload stored under `key`; nullopt when there is none or it is damaged. A hit marks the
  // entry as just used (its modification time), for the eviction order.
  std::optional<std::vector<char>> Load(const PrecomputeKey& key) const;

  // Stores `payload` under `key` (replacing a damaged entry), then removes the least recently used
  // entries until the folder's entries fit in max_bytes (never the one just stored). A cache that
  // cannot be written is skipped: it only saves time. Returns whether the entry was stored.
  bool Store(const PrecomputeKey& key, std::span<const char> payload) const;

  // The entry's file name for `key` (32 hex digits + ".precompute").
  static std::string FileName(const PrecomputeKey& key);

 private:
  std::string directory_;
  std::uint64_t max_bytes_;
};

}  // namespace combabc::plate
