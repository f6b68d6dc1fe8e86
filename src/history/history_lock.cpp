#include "history/history_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "combabc/core/error.hpp"

namespace combabc::history {
namespace {

// The pid holding an flock on the file open as `fd`, from /proc/locks; 0 when unknown.
long LockHolder(int fd) {
  struct stat file {};
  if (::fstat(fd, &file) != 0) return 0;
  const std::string inode = ":" + std::to_string(file.st_ino);
  std::ifstream locks("/proc/locks");
  std::string line;
  while (std::getline(locks, line)) {
    // "1: FLOCK  ADVISORY  WRITE 4242 fd:01:1234567 0 EOF"
    std::istringstream fields(line);
    std::string id, type, mode, access, device;
    long pid = 0;
    if (!(fields >> id >> type >> mode >> access >> pid >> device)) continue;
    if (type != "FLOCK" || device.size() < inode.size()) continue;
    if (device.compare(device.size() - inode.size(), inode.size(), inode) == 0) return pid;
  }
  return 0;
}

}  // namespace

RunLock RunLock::Acquire(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    throw Error(
        ErrorKind::kNoInput, std::string("cannot open run history: ") + std::strerror(errno), path);
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    const long holder = error == EWOULDBLOCK ? LockHolder(fd) : 0;
    ::close(fd);
    if (error != EWOULDBLOCK) {
      throw Error(
          ErrorKind::kIo, std::string("cannot lock run history: ") + std::strerror(error), path);
    }
    throw Error(ErrorKind::kCantCreate,
                "cannot write run history: another process" +
                    (holder > 0 ? " (pid " + std::to_string(holder) + ")" : std::string()) +
                    " is running or resuming this run; wait for it to end or stop it",
                path);
  }
  return RunLock(fd);
}

RunLock::RunLock(RunLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

RunLock& RunLock::operator=(RunLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

// Closing the descriptor releases the flock. (It would also drop this process's fcntl locks on
// the file, which is why HistoryStore closes its SQLite connection first.)
RunLock::~RunLock() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace combabc::history
