#include "precompute_cache.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <thread>

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace combabc::plate {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'C', 'M', 'B', 'C', 'P', 'R', 'E', '1'};
constexpr std::uint32_t kFormat = 1;
constexpr std::string_view kSuffix = ".precompute";

struct Header {
  char magic[8];
  std::uint32_t format;
  std::uint32_t reserved;
  std::uint64_t key[2];
  std::uint64_t payload_size;
  std::uint64_t checksum;
};
static_assert(sizeof(Header) == 48);

bool WriteAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool ReadAll(int fd, char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::read(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool IsEntryName(const std::string& name) {
  if (name.size() != 32 + kSuffix.size() || !name.ends_with(kSuffix)) return false;
  return std::all_of(name.begin(), name.begin() + 32, [](char c) {
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
  });
}

// Least recently used first, until the entries fit; `keep` stays whatever its size.
void Evict(const fs::path& directory, const fs::path& keep, std::uint64_t max_bytes) {
  struct Entry {
    fs::path path;
    fs::file_time_type used;
    std::uintmax_t size;
  };
  std::vector<Entry> entries;
  std::uintmax_t total = 0;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(directory, ec)) {
    if (!IsEntryName(e.path().filename().string())) continue;  // only what this cache wrote
    std::error_code stat_error;
    if (!e.is_regular_file(stat_error)) continue;
    const std::uintmax_t size = e.file_size(stat_error);
    const fs::file_time_type used = e.last_write_time(stat_error);
    if (stat_error) continue;
    total += size;
    if (e.path() != keep) entries.push_back({e.path(), used, size});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.used < b.used || (a.used == b.used && a.path < b.path);
  });
  for (const Entry& e : entries) {
    if (total <= max_bytes) break;
    std::error_code remove_error;
    if (fs::remove(e.path, remove_error)) total -= e.size;
  }
}

}  // namespace

KeyHasher::KeyHasher() : state_(XXH3_createState()) {
  XXH3_128bits_reset(static_cast<XXH3_state_t*>(state_));
}

KeyHasher::~KeyHasher() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

void KeyHasher::Add(const void* data, std::size_t size) {
  XXH3_128bits_update(static_cast<XXH3_state_t*>(state_), data, size);
}

PrecomputeKey KeyHasher::Finish() const {
  const XXH128_hash_t h = XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_));
  return {h.high64, h.low64};
}

std::string_view PlateBuildId() { return COMBABC_PLATE_BUILD_ID; }

PrecomputeCache::PrecomputeCache(std::string directory, std::uint64_t max_bytes)
    : directory_(std::move(directory)), max_bytes_(max_bytes) {}

std::string PrecomputeCache::FileName(const PrecomputeKey& key) {
  char name[33];
  std::snprintf(name,
                sizeof(name),
                "%016llx%016llx",
                static_cast<unsigned long long>(key[0]),
                static_cast<unsigned long long>(key[1]));
  return std::string(name) + std::string(kSuffix);
}

std::optional<std::vector<char>> PrecomputeCache::Load(const PrecomputeKey& key) const {
  if (directory_.empty()) return std::nullopt;
  const std::string path = (fs::path(directory_) / FileName(key)).string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  Header header{};
  std::vector<char> payload;
  struct stat st {};
  bool ok = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
            static_cast<std::uint64_t>(st.st_size) >= sizeof(Header) &&
            ReadAll(fd, reinterpret_cast<char*>(&header), sizeof(Header)) &&
            std::memcmp(header.magic, kMagic, sizeof(kMagic)) == 0 && header.format == kFormat &&
            header.key[0] == key[0] && header.key[1] == key[1] &&
            header.payload_size == static_cast<std::uint64_t>(st.st_size) - sizeof(Header);
  if (ok) {
    payload.resize(header.payload_size);
    ok = ReadAll(fd, payload.data(), payload.size()) &&
         XXH3_64bits(payload.data(), payload.size()) == header.checksum;
  }
  if (ok) ::futimens(fd, nullptr);  // just used: last in the eviction order
  ::close(fd);
  if (!ok) return std::nullopt;
  return payload;
}

bool PrecomputeCache::Store(const PrecomputeKey& key, std::span<const char> payload) const {
  if (directory_.empty()) return false;
  std::error_code ec;
  const fs::path directory(directory_);
  fs::create_directories(directory, ec);
  if (ec) return false;
  const fs::path target = directory / FileName(key);
  // A temporary of this process and thread alone, renamed into place: a reader sees the old entry
  // or the new one, never a part; two writers of one key write the same bytes.
  static std::atomic<unsigned> counter{0};
  const std::string temporary =
      target.string() + ".tmp." + std::to_string(::getpid()) + "." +
      std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id())) + "." +
      std::to_string(counter.fetch_add(1));
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return false;
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof(kMagic));
  header.format = kFormat;
  header.key[0] = key[0];
  header.key[1] = key[1];
  header.payload_size = payload.size();
  header.checksum = XXH3_64bits(payload.data(), payload.size());
  bool ok = WriteAll(fd, reinterpret_cast<const char*>(&header), sizeof(Header)) &&
            WriteAll(fd, payload.data(), payload.size());
  ok = ::close(fd) == 0 && ok;
  if (ok) ok = ::rename(temporary.c_str(), target.c_str()) == 0;
  if (!ok) {
    ::unlink(temporary.c_str());
    return false;
  }
  Evict(directory, target, max_bytes_);
  return true;
}

}  // namespace combabc::plate
