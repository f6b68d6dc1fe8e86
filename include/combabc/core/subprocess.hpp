#pragma once
// One child process for the external simulators (docs/simulators.md): started without a shell
// (posix_spawn, argv as given) in a process group of its own, with its stdin and stdout as pipes,
// its stderr to a file; every read and write bounded in bytes and in time; ended by killing the
// whole group, so that grandchildren an external program started (an FE solver under a Python
// script) never outlive the call. Used by one thread at a time.
#include <sys/types.h>

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace combabc {

using Deadline = std::chrono::steady_clock::time_point;
// now + seconds; seconds <= 0 means no deadline.
Deadline DeadlineAfter(double seconds);

struct SubprocessOptions {
  std::vector<std::string> argv;  // argv[0] is looked up in PATH when it has no '/'
  std::string working_directory;  // empty: combabc's own
  bool pipe_stdin = false;        // false: /dev/null
  std::string stderr_path;        // empty: /dev/null; else created (truncated) there
};

// How a child ended, from waitpid.
struct ExitStatus {
  int code = 0;    // exit status when signal == 0
  int signal = 0;  // the signal that ended it, or 0
  bool ok() const { return signal == 0 && code == 0; }
};
// "exited with status 3", "killed by signal 9 (SIGKILL)".
std::string Describe(const ExitStatus& status);

enum class ReadStatus { kOk, kEof, kTimeout, kTooLong };

class Subprocess {
 public:
  // Throws std::runtime_error naming argv[0] when the program cannot be started (not found, not
  // executable, bad working directory).
  explicit Subprocess(const SubprocessOptions& options);
  ~Subprocess();  // Kill() when still running
  Subprocess(const Subprocess&) = delete;
  Subprocess& operator=(const Subprocess&) = delete;

  pid_t pid() const { return pid_; }
  bool running() const { return !reaped_; }

  // Writes all of `data` to the child's stdin; false when the child closed it (or died) or the
  // deadline passed (timed_out() tells which). Never raises SIGPIPE.
  bool Write(std::string_view data, Deadline deadline);
  void CloseInput();
  // One line of stdout without its '\n'. kEof: stdout closed before a full line (a partial line
  // is left in *line); kTooLong: more than max_bytes without a '\n'.
  ReadStatus ReadLine(std::string* line, std::size_t max_bytes, Deadline deadline);
  // Checks stdout without sleeping for at most `budget`, true as soon as a read will not block.
  // A caller expecting a quick answer calls it before ReadLine: a thread that sleeps in poll()
  // lets its CPU go idle, and waking an idle CPU costs tens of microseconds on a virtual machine
  // (docs/benchmarks.md, "External simulators").
  bool SpinUntilReadable(std::chrono::nanoseconds budget);
  // All of stdout up to EOF. When the child itself exits, the rest of its group is killed so that
  // a grandchild holding stdout open cannot stall the read.
  ReadStatus ReadToEnd(std::string* out, std::size_t max_bytes, Deadline deadline);
  bool timed_out() const { return timed_out_; }
  // Waits for the child to exit (nullopt at the deadline, the child still running), then kills
  // what is left of its group and reaps it.
  std::optional<ExitStatus> Wait(Deadline deadline);
  // SIGKILL to the whole group, then reaps the child. Idempotent.
  ExitStatus Kill();

 private:
  // Polls fd and the child's exit until the deadline (false: timed out); *exited when the child
  // has exited, *readable when a read of fd will not block.
  bool WaitReadable(int fd, Deadline deadline, bool* exited, bool* readable);
  ExitStatus Reap();

  pid_t pid_ = -1;
  int stdin_fd_ = -1;
  int stdout_fd_ = -1;
  int pidfd_ = -1;  // readable once the child has exited (it stays a zombie until reaped)
  bool reaped_ = false;
  bool group_killed_ = false;
  bool timed_out_ = false;
  ExitStatus status_;
  std::string buffer_;  // stdout read past the last line returned
};

}  // namespace combabc
