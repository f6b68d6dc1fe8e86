#include "combabc/core/output_files.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;

std::string SystemError() { return std::strerror(errno); }

// "out/" names the directory "out": without this its file name would be empty.
fs::path WithoutTrailingSlash(const std::string& path) {
  fs::path p(path);
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();
  return p;
}

std::string RandomSuffix() {
  static constexpr char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz0123456789";
  std::random_device device;
  std::uniform_int_distribution<int> pick(0, static_cast<int>(sizeof kAlphabet) - 2);
  std::string suffix(8, ' ');
  for (char& c : suffix) c = kAlphabet[pick(device)];
  return suffix;
}

// What RemovePendingOutputs removes: fixed slots, as a signal handler may not allocate or lock.
// A slot is claimed (kWriting), filled, then published as a file or a directory; one that finds
// every slot taken is not registered (a later command removes its leftover as stale).
enum PendingKind : int { kFree = 0, kWriting = 1, kFile = 2, kDirectory = 3 };
struct PendingSlot {
  std::atomic<int> kind{kFree};
  char path[4096];
};
constexpr int kPendingSlots = 64;
PendingSlot pending_slots[kPendingSlots];
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free slots");

int AddPending(const std::string& path, PendingKind kind) {
  if (path.size() >= sizeof(PendingSlot::path)) return -1;
  for (int i = 0; i < kPendingSlots; ++i) {
    int expected = kFree;
    if (pending_slots[i].kind.compare_exchange_strong(expected, kWriting)) {
      std::memcpy(pending_slots[i].path, path.c_str(), path.size() + 1);
      pending_slots[i].kind.store(kind);
      return i;
    }
  }
  return -1;
}

void DropPending(int& slot) {
  if (slot >= 0) pending_slots[slot].kind.store(kFree);
  slot = -1;
}

// A temporary of ours whose process has ended: ".combabc-tmp-<pid>-..." with no process <pid>
// (a live one may be another command's at work, and a name without a pid is not recognised).
bool IsStaleTemporary(const std::string& name) {
  const std::string prefix = OutputDirectory::kTemporaryPrefix;
  if (name.rfind(prefix, 0) != 0) return false;
  std::size_t end = prefix.size();
  while (end < name.size() && end - prefix.size() < 10 && name[end] >= '0' && name[end] <= '9') {
    ++end;
  }
  if (end == prefix.size() || end >= name.size() || name[end] != '-') return false;
  const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
  if (pid <= 0 || pid == static_cast<long>(::getpid())) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

// Removes the stale temporaries (regular files only) of a directory combabc owns.
void RemoveStaleTemporaries(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!IsStaleTemporary(it->path().filename().string())) continue;
    struct stat st {};
    if (::lstat(it->path().c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
      ::unlink(it->path().c_str());
    }
  }
}

// lstat: a symlink is reported as itself, never as what it points to.
bool Lstat(const fs::path& path, struct stat* st) { return ::lstat(path.c_str(), st) == 0; }

// A manifest entry names a file directly inside the directory, nothing else.
bool IsPlainFileName(const std::string& name) {
  return !name.empty() && name != "." && name != ".." &&
         name.find_first_of("/\n\r") == std::string::npos && name != OutputDirectory::kManifest;
}

void SyncDirectory(const fs::path& dir) {
  // Makes the renames durable; best effort, as some file systems refuse fsync on a directory.
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

[[noreturn]] void ThrowExists(const std::string& path) {
  throw Error(
      ErrorKind::kCantCreate, "file exists (refusing to replace it; use --overwrite)", path);
}

[[noreturn]] void ThrowIsADirectory(const std::string& path) {
  throw Error(ErrorKind::kCantCreate,
              "is a directory (refusing to replace it; move it away or choose another path)",
              path);
}

// What is at an output directory's path now; throws for what can never be used.
struct DirectoryState {
  bool exists = false;
  bool has_manifest = false;
  bool empty = false;
  std::set<std::string> manifest;
};

DirectoryState Inspect(const fs::path& dir, const std::string& shown) {
  DirectoryState state;
  struct stat st {};
  if (!Lstat(dir, &st)) {
    if (errno != ENOENT) {
      throw Error(ErrorKind::kCantCreate, "cannot use output directory: " + SystemError(), shown);
    }
    const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(parent, ec)) {
      throw Error(
          ErrorKind::kCantCreate, "directory " + parent.string() + " does not exist", shown);
    }
    return state;
  }
  std::error_code ec;
  // The user named this path, so a symlink to a directory is used as that directory.
  if (!fs::is_directory(dir, ec)) {
    throw Error(ErrorKind::kCantCreate,
                "exists and is not a directory (refusing to replace it; choose another path)",
                shown);
  }
  state.exists = true;
  const fs::path manifest = dir / OutputDirectory::kManifest;
  if (Lstat(manifest, &st) && S_ISREG(st.st_mode)) {
    state.has_manifest = true;
    std::ifstream in(manifest);
    std::string line;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] != '#' && IsPlainFileName(line)) state.manifest.insert(line);
    }
  }
  state.empty = true;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().filename().string().rfind(OutputDirectory::kTemporaryPrefix, 0) != 0) {
      state.empty = false;
      break;
    }
  }
  if (ec) throw Error(ErrorKind::kCantCreate, "cannot read directory: " + ec.message(), shown);
  return state;
}

void RefuseForeign(const DirectoryState& state,
                   bool overwrite,
                   const std::string& shown,
                   const std::string& hint) {
  if (state.exists && !state.has_manifest && !state.empty && !overwrite) {
    throw Error(ErrorKind::kCantCreate,
                "directory exists, is not empty and was not written by combabc (it has no " +
                    std::string(OutputDirectory::kManifest) + "); " + hint,
                shown);
  }
}

}  // namespace

// ------------------------------------------------------------------------------------ AtomicFile

OutputPathKind ClassifyOutputPath(const std::string& path) {
  struct stat st {};
  if (!Lstat(path, &st)) return OutputPathKind::kMissing;
  if (S_ISLNK(st.st_mode)) {
    struct stat target {};
    // A dangling link, or one to a regular file, is a name that a rename replaces.
    if (::stat(path.c_str(), &target) != 0 || S_ISREG(target.st_mode)) {
      return OutputPathKind::kRegularFile;
    }
    st = target;
  }
  if (S_ISREG(st.st_mode)) return OutputPathKind::kRegularFile;
  if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return OutputPathKind::kStream;
  if (S_ISDIR(st.st_mode)) ThrowIsADirectory(path);
  const char* what = S_ISBLK(st.st_mode)    ? "a block device"
                     : S_ISSOCK(st.st_mode) ? "a socket"
                                            : "not a regular file";
  throw Error(ErrorKind::kCantCreate,
              std::string("is ") + what + " (refusing to write to it; choose a file path)",
              path);
}

AtomicFile::AtomicFile(std::string path, bool replace) : path_(std::move(path)), replace_(replace) {
  const fs::path target(path_);
  if (target.filename().empty() || target.filename() == "." || target.filename() == "..") {
    throw Error(ErrorKind::kCantCreate, "not a file name", path_);
  }
  const OutputPathKind kind = ClassifyOutputPath(path_);
  if (kind == OutputPathKind::kStream) {
    // Written into, never replaced (as cp and tee do): renaming a file over /dev/null would
    // replace the device for every program. A FIFO without a reader is refused, not waited for.
    fd_ = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) {
      throw Error(ErrorKind::kCantCreate,
                  errno == ENXIO ? std::string("is a FIFO with no reader (refusing to wait)")
                                 : "cannot open for writing: " + SystemError(),
                  path_);
    }
    const int flags = ::fcntl(fd_, F_GETFL);
    if (flags >= 0) ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK);
    stream_ = true;
    return;
  }
  if (kind == OutputPathKind::kRegularFile && !replace_) ThrowExists(path_);
  const fs::path dir = target.parent_path();
  for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
    const std::string temp =
        (dir / (OutputDirectory::kTemporaryPrefix + std::to_string(::getpid()) + "-" +
                RandomSuffix() + "-" + target.filename().string()))
            .string();
    fd_ = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd_ >= 0) {
      temp_path_ = temp;
      pending_ = AddPending(temp, kFile);
    } else if (errno != EEXIST) {
      throw Error(ErrorKind::kCantCreate, "cannot create file: " + SystemError(), path_);
    }
  }
  if (fd_ < 0) throw Error(ErrorKind::kCantCreate, "cannot create a temporary file", path_);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temp_path_.empty()) ::unlink(temp_path_.c_str());
  DropPending(pending_);
}

void RemovePendingOutputs() noexcept {
  // Files first: a directory goes only once empty.
  for (const PendingKind kind : {kFile, kDirectory}) {
    for (PendingSlot& slot : pending_slots) {
      if (slot.kind.load() != kind) continue;
      if (kind == kFile) {
        ::unlink(slot.path);
      } else {
        ::rmdir(slot.path);
      }
    }
  }
}

void AtomicFile::Flush() {
  const std::string text = buffer_.str();
  buffer_.str({});
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw Error(ErrorKind::kIo, "write failed: " + SystemError(), path_);
    done += static_cast<std::size_t>(n);
  }
}

void AtomicFile::Commit() {
  Flush();
  if (stream_) {
    const int closed = ::close(fd_);
    fd_ = -1;
    if (closed != 0) throw Error(ErrorKind::kIo, "write failed: " + SystemError(), path_);
    return;
  }
  if (::fsync(fd_) != 0) throw Error(ErrorKind::kIo, "write failed: " + SystemError(), path_);
  const int closed = ::close(fd_);
  fd_ = -1;
  if (closed != 0) throw Error(ErrorKind::kIo, "write failed: " + SystemError(), path_);

  int renamed = 0;
  if (replace_) {
    // Again at the last moment: a device or FIFO put there since the constructor is not replaced.
    if (ClassifyOutputPath(path_) == OutputPathKind::kStream) {
      throw Error(ErrorKind::kCantCreate,
                  "is now a device or FIFO (refusing to replace it; choose a file path)",
                  path_);
    }
    renamed = ::rename(temp_path_.c_str(), path_.c_str());
  } else {
    // Atomic "create, never replace"; file systems without RENAME_NOREPLACE get link + unlink,
    // which is just as exclusive.
    renamed = ::renameat2(AT_FDCWD, temp_path_.c_str(), AT_FDCWD, path_.c_str(), RENAME_NOREPLACE);
    if (renamed != 0 && (errno == EINVAL || errno == ENOSYS)) {
      renamed = ::link(temp_path_.c_str(), path_.c_str());
      if (renamed == 0) ::unlink(temp_path_.c_str());
    }
  }
  if (renamed != 0) {
    if (errno == EEXIST) ThrowExists(path_);
    if (errno == EISDIR || errno == ENOTEMPTY) ThrowIsADirectory(path_);
    throw Error(ErrorKind::kCantCreate, "cannot write: " + SystemError(), path_);
  }
  temp_path_.clear();
  DropPending(pending_);
  SyncDirectory(fs::path(path_).parent_path());
}

void WriteFileAtomically(const std::string& path, std::string_view text, bool overwrite) {
  AtomicFile file(path, overwrite);
  file.out() << text;
  file.Commit();
}

// ------------------------------------------------------------------------------- OutputDirectory

void OutputDirectory::Check(const std::string& path, bool overwrite, const std::string& hint) {
  RefuseForeign(Inspect(WithoutTrailingSlash(path), path), overwrite, path, hint);
}

OutputDirectory::OutputDirectory(std::string path, bool overwrite)
    : path_(std::move(path)), overwrite_(overwrite) {
  const fs::path dir = WithoutTrailingSlash(path_);
  const DirectoryState state = Inspect(dir, path_);
  RefuseForeign(state, overwrite_, path_, kDefaultHint);
  previous_ = state.manifest;
  if (!state.exists) {
    if (::mkdir(dir.c_str(), 0777) != 0) {
      throw Error(ErrorKind::kCantCreate, "cannot create directory: " + SystemError(), path_);
    }
    created_ = true;
    pending_ = AddPending(dir.string(), kDirectory);
  } else if (state.has_manifest || state.empty) {
    // combabc's directory: what an interrupted or killed command of ours left is removed.
    RemoveStaleTemporaries(dir);
  }
}

OutputDirectory::~OutputDirectory() {
  staged_.clear();  // removes the temporaries of an uncommitted directory
  if (created_ && !committed_) ::rmdir(WithoutTrailingSlash(path_).c_str());
  DropPending(pending_);
}

std::ostream& OutputDirectory::Add(const std::string& name) {
  if (!IsPlainFileName(name)) {
    throw Error(ErrorKind::kSoftware, "not a plain file name: \"" + name + "\"", path_);
  }
  for (const auto& [staged, file] : staged_) {
    if (staged == name) throw Error(ErrorKind::kSoftware, "written twice: " + name, path_);
  }
  // A report or export file is a file: a device or FIFO of that name is refused, never written.
  const std::string entry = (WithoutTrailingSlash(path_) / name).string();
  if (ClassifyOutputPath(entry) == OutputPathKind::kStream) {
    throw Error(ErrorKind::kCantCreate,
                "is a device or FIFO (refusing to write combabc's " + name +
                    " into it; choose another directory)",
                entry);
  }
  // combabc's own files (listed in the manifest) may be replaced; others only with overwrite.
  const bool replace = overwrite_ || previous_.count(name) != 0;
  staged_.emplace_back(
      name, std::make_unique<AtomicFile>((WithoutTrailingSlash(path_) / name).string(), replace));
  return staged_.back().second->out();
}

bool OutputDirectory::Has(const std::string& name) const {
  for (const auto& entry : staged_) {
    if (entry.first == name) return true;
  }
  return false;
}

std::string OutputDirectory::StagedPath(const std::string& name) {
  for (const auto& [staged, file] : staged_) {
    if (staged == name) {
      file->Flush();
      return file->temporary_path();
    }
  }
  throw Error(ErrorKind::kSoftware, "not staged: " + name, path_);
}

void OutputDirectory::Discard(const std::string& name) {
  std::erase_if(staged_, [&](const auto& staged) { return staged.first == name; });
}

void OutputDirectory::Commit() {
  const fs::path dir = WithoutTrailingSlash(path_);
  // Every check again (the directory may have changed since Add), so that a refusal changes
  // nothing: no file is renamed into place before all of them are known to be allowed.
  std::set<std::string> written;
  for (const auto& [name, file] : staged_) {
    struct stat st {};
    if (Lstat(dir / name, &st)) {
      if (S_ISDIR(st.st_mode)) ThrowIsADirectory(file->path());
      if (ClassifyOutputPath(file->path()) != OutputPathKind::kRegularFile) {
        throw Error(ErrorKind::kCantCreate,
                    "is not a regular file (refusing to replace it; move it away or choose another "
                    "directory)",
                    file->path());
      }
      if (!overwrite_ && !(previous_.count(name) != 0 && S_ISREG(st.st_mode))) {
        throw Error(ErrorKind::kCantCreate,
                    "file exists and was not written by combabc (refusing to replace it; use "
                    "--overwrite)",
                    file->path());
      }
    }
    written.insert(name);
  }
  // The manifest lists old and new files while they are swapped, so that an interrupted commit
  // still leaves every combabc file listed; then only the new ones.
  const auto write_manifest = [&](const std::set<std::string>& names) {
    std::string text =
        "# Files combabc wrote in this directory; combabc replaces only these here.\n";
    for (const std::string& name : names) text += name + '\n';
    WriteFileAtomically((dir / kManifest).string(), text, /*overwrite=*/true);
  };
  std::set<std::string> both = previous_;
  both.insert(written.begin(), written.end());
  write_manifest(both);
  for (const auto& [name, file] : staged_) file->Commit();
  for (const std::string& name : previous_) {
    struct stat st {};
    if (written.count(name) == 0 && Lstat(dir / name, &st) && S_ISREG(st.st_mode)) {
      ::unlink((dir / name).c_str());  // a file of combabc's previous output, not written now
    }
  }
  write_manifest(written);
  committed_ = true;
  DropPending(pending_);
}

}  // namespace combabc
