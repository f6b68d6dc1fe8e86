#pragma once
// The writer's lock on a run history (private to src/history): one process at a time may run or
// resume a run. An flock(2) on the database file itself: it does not interact with SQLite's
// fcntl(2) locks, and the kernel releases it when the process ends, however it ends.
#include <string>

namespace combabc::history {

class RunLock {
 public:
  RunLock() = default;
  // Locks `path` (which must exist) exclusively, or throws kCantCreate naming the process that
  // holds it, when the kernel says (Linux /proc/locks).
  static RunLock Acquire(const std::string& path);
  RunLock(RunLock&& other) noexcept;
  RunLock& operator=(RunLock&& other) noexcept;
  RunLock(const RunLock&) = delete;
  ~RunLock();

 private:
  explicit RunLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace combabc::history
