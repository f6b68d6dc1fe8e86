#include "plate/fast_path/precompute_cache.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <set>
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
constexpr std::string_view kTemporary = ".tmp.";  // <entry name>.tmp.<pid>.<thread>.<count>
constexpr std::size_t kBufferBytes = std::size_t{1} << 16;

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

bool IsHex32(const std::string& name) {
  return name.size() >= 32 && std::all_of(name.begin(), name.begin() + 32, [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

bool IsEntryName(const std::string& name) {
  return IsHex32(name) && name.size() == 32 + kSuffix.size() && name.ends_with(kSuffix);
}

// The temporary of a writer (Store), which a crash may leave behind.
bool IsTemporaryName(const std::string& name) {
  return IsHex32(name) && name.compare(32, kSuffix.size(), kSuffix) == 0 &&
         name.compare(32 + kSuffix.size(), kTemporary.size(), kTemporary) == 0;
}

// Group or others may write it.
bool SharedWritable(const struct stat& st) { return (st.st_mode & (S_IWGRP | S_IWOTH)) != 0; }

std::string Octal(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

// Creates the folders of `directory` that do not exist, each owner-only (0700) whatever the
// umask: an entry must not be writable by anyone else from the moment it exists. Folders that
// exist are left as they are (never changed: the user may have chosen their modes).
void CreatePrivateFolders(const fs::path& directory) {
  std::error_code ec;
  fs::path at;
  for (const fs::path& part : fs::absolute(directory, ec).lexically_normal()) {
    at /= part;
    if (part.empty() || at == at.root_path()) continue;
    if (::mkdir(at.c_str(), 0700) == 0) ::chmod(at.c_str(), 0700);
  }
}

// The sink of UntrustedCacheWarning: stderr, once per folder and process.
std::mutex warn_mutex;
std::function<void(const std::string&)>& WarnSink() {
  static std::function<void(const std::string&)> sink = [](const std::string& message) {
    std::cerr << "combabc: warning: " << message << "\n";
  };
  return sink;
}

void WarnOnce(const std::string& directory, const std::string& why) {
  const std::lock_guard<std::mutex> lock(warn_mutex);
  static std::set<std::string> warned;
  if (!warned.insert(directory).second) return;
  if (WarnSink()) {
    WarnSink()("the precompute cache " + directory + " is not used (" + why +
               "): the sensor's pieces are built afresh (docs/model.md, \"Who the cache trusts\")");
  }
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
  const fs::file_time_type stale = fs::file_time_type::clock::now() - std::chrono::hours(1);
  for (const fs::directory_entry& e : fs::directory_iterator(directory, ec)) {
    const std::string name = e.path().filename().string();
    std::error_code stat_error;
    if (IsTemporaryName(name) && e.last_write_time(stat_error) < stale && !stat_error) {
      fs::remove(e.path(), stat_error);  // a writer that died an hour ago or more
      continue;
    }
    if (!IsEntryName(name)) continue;  // only what this cache wrote
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

std::string UntrustedCacheFolder(const std::string& directory) {
  // As ssh's StrictModes treats ~/.ssh: every folder on the way, links resolved, must be owned by
  // this user or root and writable by nobody else (or sticky, as /tmp: others cannot then rename
  // or remove what is ours); the cache folder itself must be this user's.
  std::error_code ec;
  const fs::path real = fs::canonical(directory, ec);
  if (ec) return "cannot resolve " + directory + ": " + ec.message();
  const uid_t me = ::geteuid();
  fs::path at;
  for (const fs::path& part : real) {
    at /= part;
    struct stat st {};
    if (::stat(at.c_str(), &st) != 0) return "cannot stat " + at.string();
    const bool last = at == real;
    if (last && !S_ISDIR(st.st_mode)) return real.string() + " is not a folder";
    if (last ? st.st_uid != me : st.st_uid != me && st.st_uid != 0) {
      return at.string() + " is owned by user " + std::to_string(st.st_uid) + ", not by user " +
             std::to_string(me);
    }
    if (SharedWritable(st) && (last || (st.st_mode & S_ISVTX) == 0)) {
      return at.string() + " is writable by group or others (mode " + Octal(st.st_mode) +
             "; chmod go-w it)";
    }
  }
  return "";
}

void SetUntrustedCacheWarning(std::function<void(const std::string&)> sink) {
  const std::lock_guard<std::mutex> lock(warn_mutex);
  WarnSink() = std::move(sink);
}

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

bool PrecomputeCache::Load(const PrecomputeKey& key,
                           std::uint64_t max_payload_bytes,
                           const std::function<bool(ByteReader&)>& read) const {
  if (directory_.empty()) return false;
  std::error_code ec;
  if (!fs::exists(directory_, ec)) return false;  // nothing stored yet
  if (const std::string why = UntrustedCacheFolder(directory_); !why.empty()) {
    WarnOnce(directory_, why);
    return false;
  }
  const std::string path = (fs::path(directory_) / FileName(key)).string();
  // Not blocking (a FIFO planted at the name would block open() for ever), not following a link;
  // then only a regular file of this user's, writable by nobody else, of a size the caller's
  // model can need: nothing is allocated for a file that fails these.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return false;
  Header header{};
  struct stat st {};
  bool ok = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == ::geteuid() &&
            !SharedWritable(st) && static_cast<std::uint64_t>(st.st_size) >= sizeof(Header) &&
            static_cast<std::uint64_t>(st.st_size) - sizeof(Header) <= max_payload_bytes &&
            ReadAll(fd, reinterpret_cast<char*>(&header), sizeof(Header)) &&
            std::memcmp(header.magic, kMagic, sizeof(kMagic)) == 0 && header.format == kFormat &&
            header.key[0] == key[0] && header.key[1] == key[1] &&
            header.payload_size == static_cast<std::uint64_t>(st.st_size) - sizeof(Header);
  if (ok) {
    ByteReader reader(fd, header.payload_size);
    ok =
        read(reader) && !reader.failed() && reader.at_end() && reader.checksum() == header.checksum;
  }
  if (ok) ::futimens(fd, nullptr);  // just used: last in the eviction order
  ::close(fd);
  return ok;
}

bool PrecomputeCache::Store(const PrecomputeKey& key,
                            const std::function<void(ByteWriter&)>& write) const {
  if (directory_.empty()) return false;
  const fs::path directory(directory_);
  CreatePrivateFolders(directory);
  // Nothing is written, replaced or evicted in a folder that others could write: it is not ours
  // to keep (docs/model.md, "Who the cache trusts").
  if (const std::string why = UntrustedCacheFolder(directory_); !why.empty()) {
    WarnOnce(directory_, why);
    return false;
  }
  const fs::path target = directory / FileName(key);
  // A temporary of this process and thread alone, renamed into place: a reader sees the old entry
  // or the new one, never a part; two writers of one key write the same bytes.
  static std::atomic<unsigned> counter{0};
  const std::string temporary =
      target.string() + std::string(kTemporary) + std::to_string(::getpid()) + "." +
      std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id())) + "." +
      std::to_string(counter.fetch_add(1));
  const int fd =
      ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) return false;
  // The header last, once the payload's size and checksum are known.
  Header header{};
  bool ok = ::lseek(fd, sizeof(Header), SEEK_SET) == static_cast<off_t>(sizeof(Header));
  if (ok) {
    ByteWriter writer(fd);
    write(writer);
    ok = writer.Flush();
    header.payload_size = writer.size();
    header.checksum = writer.checksum();
  }
  std::memcpy(header.magic, kMagic, sizeof(kMagic));
  header.format = kFormat;
  header.key[0] = key[0];
  header.key[1] = key[1];
  ok = ok && ::pwrite(fd, &header, sizeof(Header), 0) == static_cast<ssize_t>(sizeof(Header));
  ok = ::close(fd) == 0 && ok;
  if (ok) ok = ::rename(temporary.c_str(), target.c_str()) == 0;
  if (!ok) {
    ::unlink(temporary.c_str());
    return false;
  }
  Evict(directory, target, max_bytes_);
  return true;
}

ByteWriter::ByteWriter(int fd) : fd_(fd), state_(XXH3_createState()) {
  XXH3_64bits_reset(static_cast<XXH3_state_t*>(state_));
  buffer_.reserve(kBufferBytes);
}

ByteWriter::~ByteWriter() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

void ByteWriter::Put(const void* data, std::size_t size) {
  XXH3_64bits_update(static_cast<XXH3_state_t*>(state_), data, size);
  size_ += size;
  const auto* p = static_cast<const char*>(data);
  if (buffer_.size() + size > kBufferBytes) Flush();
  if (size >= kBufferBytes) {
    ok_ = ok_ && WriteAll(fd_, p, size);  // a matrix: straight from its memory
  } else {
    buffer_.insert(buffer_.end(), p, p + size);
  }
}

bool ByteWriter::Flush() {
  ok_ = ok_ && WriteAll(fd_, buffer_.data(), buffer_.size());
  buffer_.clear();
  return ok_;
}

std::uint64_t ByteWriter::checksum() const {
  return XXH3_64bits_digest(static_cast<XXH3_state_t*>(state_));
}

ByteReader::ByteReader(int fd, std::uint64_t size)
    : fd_(fd), left_(size), file_left_(size), state_(XXH3_createState()) {
  XXH3_64bits_reset(static_cast<XXH3_state_t*>(state_));
}

ByteReader::~ByteReader() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

void ByteReader::Get(void* data, std::size_t size) {
  if (failed_ || size > left_) {
    failed_ = true;
    std::memset(data, 0, size);
    return;
  }
  auto* p = static_cast<char*>(data);
  std::size_t done = 0;
  while (done < size) {
    if (buffer_at_ == buffer_.size()) {
      if (size - done >= kBufferBytes) {
        // A matrix: straight into its memory.
        if (size - done > file_left_ || !ReadAll(fd_, p + done, size - done)) {
          failed_ = true;
          return;
        }
        file_left_ -= size - done;
        break;
      }
      const auto want = static_cast<std::size_t>(std::min<std::uint64_t>(kBufferBytes, file_left_));
      buffer_.resize(want);
      buffer_at_ = 0;
      if (want == 0 || !ReadAll(fd_, buffer_.data(), want)) {
        failed_ = true;
        return;
      }
      file_left_ -= want;
    }
    const std::size_t n = std::min(size - done, buffer_.size() - buffer_at_);
    std::memcpy(p + done, buffer_.data() + buffer_at_, n);
    buffer_at_ += n;
    done += n;
  }
  left_ -= size;
  XXH3_64bits_update(static_cast<XXH3_state_t*>(state_), data, size);
}

std::uint64_t ByteReader::checksum() const {
  return XXH3_64bits_digest(static_cast<XXH3_state_t*>(state_));
}

}  // namespace combabc::plate
