#pragma once
// combabc's one way to run a child process: the external simulators (docs/simulators.md) and the
// Python scripts of scripts/report/ (services' RunProcess). Started without a shell (posix_spawn,
// argv as given) in a process group of its own, with its stdin and stdout as pipes, its stderr
// drained through a pipe into a file and/or memory that keep only the last kMaxStderrBytes; every
// read and write bounded in bytes and in time; ended by killing the whole group, so that
// grandchildren an external program started (an FE solver under a Python script) never outlive
// the call. Used by one thread at a time.
#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace combabc {

using Deadline = std::chrono::steady_clock::time_point;
// now + seconds; seconds <= 0 means no deadline.
Deadline DeadlineAfter(double seconds);

// The most of a child's stderr that is kept, in memory and in its stderr file: the last 64 KiB.
// A program that writes without end can neither fill the disk nor combabc's memory, and its
// failure reason is the last line of what is kept.
inline constexpr std::size_t kMaxStderrBytes = std::size_t{64} << 10;

struct SubprocessOptions {
  std::vector<std::string> argv;  // argv[0] is looked up in PATH when it has no '/'
  // false: argv[0] is a path as it stands (relative to combabc's folder), never looked up in
  // PATH: the file a caller checked is the file that runs.
  bool search_path = true;
  std::string working_directory;  // empty: combabc's own
  bool pipe_stdin = false;        // false: /dev/null
  bool pipe_stdout = true;        // false: /dev/null (the reads see end of file)
  // Empty: /dev/null (unless capture_stderr). Else the child's stderr is a pipe that combabc
  // drains (while it waits on the child in any way, and when the child ends) into this file,
  // created (truncated) here and holding at most the last kMaxStderrBytes.
  std::string stderr_path;
  // The stderr pipe even without a file: its last kMaxStderrBytes in memory (Stderr()).
  bool capture_stderr = false;
  // With a stderr pipe: hears each line of stderr (without its newline) as it is drained; a line
  // it returns true for (a progress line) is not kept. A line longer than kMaxStderrBytes, and an
  // unended last line, are kept unheard.
  std::function<bool(const std::string&)> on_stderr_line;
};

// The program could not be started (posix_spawn failed): error() is its errno (ENOENT, EACCES,
// ENOEXEC), for callers that word the failure themselves.
class SpawnError : public std::runtime_error {
 public:
  SpawnError(const std::string& what, int error) : std::runtime_error(what), error_(error) {}
  int error() const { return error_; }

 private:
  int error_;
};

// While one lives, SIGINT and SIGTERM (those not ignored) are recorded instead of taking their
// course, so that a child can be interrupted and reaped before combabc ends by the signal
// (Subprocess::WaitForwarding); the previous handlers come back at Release() or when it goes.
// One at a time, made before the child is spawned.
class SignalHold {
 public:
  SignalHold();
  ~SignalHold() { Release(); }
  SignalHold(const SignalHold&) = delete;
  SignalHold& operator=(const SignalHold&) = delete;
  // The signal recorded since the hold began, or 0.
  int signal() const;
  void Release();

 private:
  static constexpr int kSignals[2] = {SIGINT, SIGTERM};
  struct sigaction old_[2] = {};
  bool installed_[2] = {false, false};
};

// How a child ended, from waitpid.
struct ExitStatus {
  int code = 0;    // exit status when signal == 0
  int signal = 0;  // the signal that ended it, or 0
  bool ok() const { return signal == 0 && code == 0; }
};
// "exited with status 3", "killed by signal 9 (SIGKILL)".
std::string Describe(const ExitStatus& status);

// Why `program` (an argv[0]) cannot be started, looked up as posix_spawnp and execvp do: a name
// without '/' in the directories of PATH (default "/bin:/usr/bin"), a path as it is; empty when it
// names an executable regular file. Relative paths (and PATH entries) are taken relative to
// `working_directory`, the one the child starts in, lexically (it need not exist yet).
std::string ProgramProblem(const std::string& program, const std::string& working_directory);

enum class ReadStatus { kOk, kEof, kTimeout, kTooLong };

class Subprocess {
 public:
  // Throws std::runtime_error naming argv[0] when the program cannot be started (not found, not
  // executable, bad working directory) or its stderr file cannot be created.
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
  // Wait() without a deadline, but once `hold` has recorded a signal the child is interrupted:
  // SIGINT to its group (a Python script stops on KeyboardInterrupt and cleans up), SIGKILL
  // `grace` later if it is still running. A held signal is seen within 0.1 s.
  ExitStatus WaitForwarding(const SignalHold& hold, std::chrono::milliseconds grace);
  // SIGKILL to the whole group, then reaps the child. Idempotent.
  ExitStatus Kill();
  // True when stdout holds more than the lines returned so far: bytes already read, or bytes
  // waiting in the pipe (read now, without blocking). A protocol of one line per request uses it
  // to notice a child that wrote more than its answer.
  bool OutputPending();
  // The last non-empty line of the child's stderr (of its last kMaxStderrBytes), drained up to
  // now; empty when none.
  std::string LastStderrLine();
  // The child's stderr drained up to now: its last kMaxStderrBytes, less the lines on_stderr_line
  // took.
  std::string Stderr();

 private:
  // Polls fd for `events` (fd < 0: none), the child's exit and its stderr (drained as it comes)
  // until fd is ready or the child has exited; false at the deadline. *exited when the child has
  // exited, *ready when fd is ready (a read or write will not block).
  bool WaitFor(int fd, short events, Deadline deadline, bool* exited, bool* ready);
  // Reads what the stderr pipe holds now (never blocks) into stderr_tail_ and the stderr file.
  void DrainStderr();
  // Passes what was drained through on_stderr_line_ (when set) to KeepStderr.
  void HearStderr(const char* data, std::size_t size);
  void KeepStderr(const char* data, std::size_t size);
  // No more stderr: the pipe closed, an unended last line kept.
  void CloseStderr();
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
  int stderr_fd_ = -1;  // the stderr pipe, non-blocking; -1 when none or at its end
  int stderr_file_ = -1;
  std::size_t stderr_file_size_ = 0;
  std::string stderr_tail_;  // the last kMaxStderrBytes of stderr, what the file holds
  std::function<bool(const std::string&)> on_stderr_line_;
  std::string stderr_line_;  // with on_stderr_line_: the start of a line not yet ended
};

}  // namespace combabc
