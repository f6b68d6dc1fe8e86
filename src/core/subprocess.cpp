#include "combabc/core/subprocess.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

extern "C" char** environ;  // NOLINT(readability-redundant-declaration): POSIX declares it nowhere

namespace combabc {
namespace {

using Clock = std::chrono::steady_clock;

int RemainingMs(Deadline deadline) {
  if (deadline == Deadline::max()) return -1;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  // Rounded up: a deadline 0.4 ms away is still waited for, not busy-polled.
  return left.count() < 0 ? 0 : static_cast<int>(left.count()) + 1;
}

void CloseFd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

std::string SignalName(int signal) {
  const char* abbrev = ::sigabbrev_np(signal);
  return abbrev != nullptr ? std::string("SIG") + abbrev : "signal " + std::to_string(signal);
}

// The spawn's attribute and file-action objects, destroyed on every path.
struct SpawnSetup {
  posix_spawnattr_t attr{};
  posix_spawn_file_actions_t actions{};
  SpawnSetup() {
    posix_spawnattr_init(&attr);
    posix_spawn_file_actions_init(&actions);
  }
  ~SpawnSetup() {
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
  }
  SpawnSetup(const SpawnSetup&) = delete;
  SpawnSetup& operator=(const SpawnSetup&) = delete;
};

}  // namespace

Deadline DeadlineAfter(double seconds) {
  if (!(seconds > 0.0)) return Deadline::max();
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string ProgramProblem(const std::string& program, const std::string& working_directory) {
  if (program.empty()) return "no program named";
  auto problem = [&](const std::string& given) -> std::string {
    const std::filesystem::path path =
        given.front() == '/' || working_directory.empty()
            ? std::filesystem::path(given)
            : (std::filesystem::path(working_directory) / given).lexically_normal();
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return std::strerror(errno);
    if (!S_ISREG(st.st_mode)) return "not a regular file";
    if (::access(path.c_str(), X_OK) != 0) return "not executable";
    return {};
  };
  if (program.find('/') != std::string::npos) {
    std::string why = problem(program);
    if (why.empty()) return why;
    return program + ": " + why +
           (program.front() == '/' ? ""
                                   : " (relative to the folder the program starts in; use an "
                                     "absolute path or {config_dir}/...)");
  }
  const char* env = std::getenv("PATH");
  const std::string path = env != nullptr ? env : "/bin:/usr/bin";
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = std::min(path.find(':', begin), path.size());
    // An empty entry is the current directory, as for execvp.
    std::string candidate = end > begin ? path.substr(begin, end - begin) : ".";
    candidate += '/';
    candidate += program;
    if (problem(candidate).empty()) return {};
    if (end == path.size()) break;
    begin = end + 1;
  }
  return "'" + program + "' is not an executable file in any directory of PATH";
}

std::string Describe(const ExitStatus& status) {
  if (status.signal != 0) {
    return "killed by signal " + std::to_string(status.signal) + " (" + SignalName(status.signal) +
           ")";
  }
  return "exited with status " + std::to_string(status.code);
}

Subprocess::Subprocess(const SubprocessOptions& options) {
  if (options.argv.empty() || options.argv.front().empty()) {
    throw std::runtime_error("no program to run (empty argv)");
  }
  // stdin: a socket, so that writing to a child that went away fails with EPIPE under
  // MSG_NOSIGNAL instead of raising SIGPIPE in combabc. stdout: a pipe. Both close-on-exec here,
  // so a child spawned by another thread at the same time never inherits this child's ends.
  int in[2] = {-1, -1};
  int out[2] = {-1, -1};
  int err[2] = {-1, -1};
  auto close_all = [&] {
    for (int* fd : {&in[0], &in[1], &out[0], &out[1], &err[0], &err[1], &stderr_file_}) {
      CloseFd(*fd);
    }
  };
  auto fail = [&](const std::string& what, int error) {
    close_all();
    throw std::runtime_error(what + ": " + std::strerror(error));
  };
  if (options.pipe_stdin &&
      ::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, static_cast<int*>(in)) != 0) {
    fail("cannot create a pipe", errno);
  }
  if (options.pipe_stdout && ::pipe2(static_cast<int*>(out), O_CLOEXEC) != 0) {
    fail("cannot create a pipe", errno);
  }
  if (!options.stderr_path.empty() || options.capture_stderr) {
    // stderr: a pipe that combabc drains into memory and the file, keeping its tail
    // (kMaxStderrBytes), so that a program writing without end fills neither the disk nor
    // combabc's memory.
    if (::pipe2(static_cast<int*>(err), O_CLOEXEC) != 0) fail("cannot create a pipe", errno);
    if (::fcntl(err[0], F_SETFL, O_NONBLOCK) != 0) fail("cannot create a pipe", errno);
  }
  if (!options.stderr_path.empty()) {
    stderr_file_ =
        ::open(options.stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (stderr_file_ < 0) fail("cannot create " + options.stderr_path, errno);
  }
  on_stderr_line_ = options.on_stderr_line;
  SpawnSetup s;
  // A new process group (pgid = the child's pid), default signal dispositions (combabc's
  // ignored SIGPIPE must not leak into the program) and an empty signal mask.
  sigset_t defaults;
  sigset_t empty;
  sigfillset(&defaults);
  sigemptyset(&empty);
  posix_spawnattr_setsigdefault(&s.attr, &defaults);
  posix_spawnattr_setsigmask(&s.attr, &empty);
  posix_spawnattr_setpgroup(&s.attr, 0);
  posix_spawnattr_setflags(
      &s.attr,
      static_cast<short>(POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK));
  if (options.pipe_stdin) {
    posix_spawn_file_actions_adddup2(&s.actions, in[1], STDIN_FILENO);
  } else {
    posix_spawn_file_actions_addopen(&s.actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  }
  if (options.pipe_stdout) {
    posix_spawn_file_actions_adddup2(&s.actions, out[1], STDOUT_FILENO);
  } else {
    posix_spawn_file_actions_addopen(&s.actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  }
  if (err[1] >= 0) {
    posix_spawn_file_actions_adddup2(&s.actions, err[1], STDERR_FILENO);
  } else {
    posix_spawn_file_actions_addopen(&s.actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  }
  if (!options.working_directory.empty()) {
    posix_spawn_file_actions_addchdir_np(&s.actions, options.working_directory.c_str());
  }
  std::vector<char*> argv;
  argv.reserve(options.argv.size() + 1);
  for (const std::string& a : options.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const int rc = options.search_path
                     ? ::posix_spawnp(&pid_, argv[0], &s.actions, &s.attr, argv.data(), environ)
                     : ::posix_spawn(&pid_, argv[0], &s.actions, &s.attr, argv.data(), environ);
  if (rc != 0) {
    pid_ = -1;
    reaped_ = true;
    close_all();
    throw SpawnError("cannot start " + options.argv.front() + ": " + std::strerror(rc), rc);
  }
  CloseFd(in[1]);
  CloseFd(out[1]);
  CloseFd(err[1]);
  stdin_fd_ = in[0];
  stdout_fd_ = out[0];
  stderr_fd_ = err[0];
  pidfd_ = static_cast<int>(::syscall(SYS_pidfd_open, pid_, 0));
  if (pidfd_ < 0) {
    const int e = errno;
    Kill();
    for (int* fd : {&stdin_fd_, &stdout_fd_, &stderr_fd_, &stderr_file_}) CloseFd(*fd);
    throw std::runtime_error(std::string("cannot watch the child process: ") + std::strerror(e));
  }
}

Subprocess::~Subprocess() {
  if (!reaped_) Kill();
  CloseFd(stdin_fd_);
  CloseFd(stdout_fd_);
  CloseFd(pidfd_);
  CloseFd(stderr_fd_);
  CloseFd(stderr_file_);
}

bool Subprocess::Write(std::string_view data, Deadline deadline) {
  while (!data.empty()) {
    if (stdin_fd_ < 0) return false;
    const ssize_t n = ::send(stdin_fd_, data.data(), data.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      data.remove_prefix(static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      bool exited = false;
      bool ready = false;
      if (!WaitFor(stdin_fd_, POLLOUT, deadline, &exited, &ready)) return false;
      // A child that exited cannot read what is left (a grandchild holding its stdin might).
      if (!ready) return false;
      continue;
    }
    return false;  // EPIPE, ECONNRESET: the child closed its stdin or died
  }
  return true;
}

void Subprocess::CloseInput() { CloseFd(stdin_fd_); }

bool Subprocess::WaitFor(int fd, short events, Deadline deadline, bool* exited, bool* ready) {
  *ready = false;
  if (group_killed_) *exited = true;
  if (fd < 0 && *exited) return true;
  for (;;) {
    pollfd p[3];
    nfds_t n = 0;
    const nfds_t fd_slot = n;
    if (fd >= 0) p[n++] = {fd, events, 0};
    // Once the exit was seen and the group killed, the child's exit is no longer waited for.
    const nfds_t exit_slot = n;
    if (!group_killed_) p[n++] = {pidfd_, POLLIN, 0};
    const nfds_t stderr_slot = n;
    if (stderr_fd_ >= 0) p[n++] = {stderr_fd_, POLLIN, 0};
    const int r = ::poll(static_cast<pollfd*>(p), n, RemainingMs(deadline));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) {
      timed_out_ = true;
      return false;
    }
    if (stderr_fd_ >= 0 && p[stderr_slot].revents != 0) DrainStderr();
    if (!group_killed_ && (p[exit_slot].revents & POLLIN) != 0) *exited = true;
    // Data, end of file or an error: the read or write will not block.
    if (fd >= 0) *ready = p[fd_slot].revents != 0;
    if (*ready || *exited) return true;
  }
}

void Subprocess::DrainStderr() {
  char chunk[16384];
  while (stderr_fd_ >= 0) {
    const ssize_t n = ::read(stderr_fd_, static_cast<char*>(chunk), sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    if (n <= 0) {
      CloseStderr();  // end of file (every writer gone) or an error: nothing more comes
      return;
    }
    HearStderr(static_cast<const char*>(chunk), static_cast<std::size_t>(n));
  }
}

void Subprocess::HearStderr(const char* data, std::size_t size) {
  if (!on_stderr_line_) {
    KeepStderr(data, size);
    return;
  }
  stderr_line_.append(data, size);
  std::size_t start = 0;
  for (std::size_t end = 0; (end = stderr_line_.find('\n', start)) != std::string::npos;
       start = end + 1) {
    if (!on_stderr_line_(stderr_line_.substr(start, end - start))) {
      KeepStderr(stderr_line_.data() + start, end + 1 - start);
    }
  }
  stderr_line_.erase(0, start);
  // A line longer than what is kept is no progress line: kept as it comes.
  if (stderr_line_.size() > kMaxStderrBytes) {
    KeepStderr(stderr_line_.data(), stderr_line_.size());
    stderr_line_.clear();
  }
}

void Subprocess::CloseStderr() {
  CloseFd(stderr_fd_);
  KeepStderr(stderr_line_.data(), stderr_line_.size());
  stderr_line_.clear();
}

void Subprocess::KeepStderr(const char* data, std::size_t size) {
  if (size == 0) return;
  stderr_tail_.append(data, size);
  if (stderr_tail_.size() > kMaxStderrBytes) {
    stderr_tail_.erase(0, stderr_tail_.size() - kMaxStderrBytes);
  }
  if (stderr_file_ < 0) return;
  // The file is diagnostics only: a failed write (disk full) loses some of it, nothing else.
  auto write_at = [&](const char* bytes, std::size_t count, std::size_t offset) {
    while (count > 0) {
      const ssize_t w = ::pwrite(stderr_file_, bytes, count, static_cast<off_t>(offset));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) return false;
      bytes += w;
      count -= static_cast<std::size_t>(w);
      offset += static_cast<std::size_t>(w);
    }
    return true;
  };
  if (stderr_file_size_ + size <= kMaxStderrBytes) {
    if (write_at(data, size, stderr_file_size_)) stderr_file_size_ += size;
    return;
  }
  // Full: the file is rewritten with the tail kept in memory.
  if (write_at(stderr_tail_.data(), stderr_tail_.size(), 0) &&
      ::ftruncate(stderr_file_, static_cast<off_t>(stderr_tail_.size())) == 0) {
    stderr_file_size_ = stderr_tail_.size();
  }
}

std::string Subprocess::Stderr() {
  DrainStderr();
  return stderr_tail_;
}

std::string Subprocess::LastStderrLine() {
  DrainStderr();
  std::size_t end = stderr_tail_.find_last_not_of("\r\n");
  if (end == std::string::npos) return {};
  const std::size_t begin = stderr_tail_.find_last_of("\r\n", end);
  const std::size_t first = begin == std::string::npos ? 0 : begin + 1;
  return stderr_tail_.substr(first, end + 1 - first);
}

bool Subprocess::OutputPending() {
  if (!buffer_.empty()) return true;
  if (stdout_fd_ < 0) return false;
  pollfd p{stdout_fd_, POLLIN, 0};
  if (::poll(&p, 1, 0) <= 0 || (p.revents & POLLIN) == 0) return false;
  char chunk[4096];
  ssize_t n = 0;
  do {
    n = ::read(stdout_fd_, static_cast<char*>(chunk), sizeof chunk);
  } while (n < 0 && errno == EINTR);
  if (n <= 0) return false;  // end of file: nothing pending (the next read sees it too)
  buffer_.append(static_cast<const char*>(chunk), static_cast<std::size_t>(n));
  return true;
}

bool Subprocess::SpinUntilReadable(std::chrono::nanoseconds budget) {
  if (buffer_.find('\n') != std::string::npos) return true;
  const auto end = std::chrono::steady_clock::now() + budget;
  do {
    pollfd p{stdout_fd_, POLLIN, 0};
    if (::poll(&p, 1, 0) > 0) return true;
    // Lets a worker that shares this CPU run at once instead of at the end of our time slice.
    ::sched_yield();
  } while (std::chrono::steady_clock::now() < end);
  return false;
}

ReadStatus Subprocess::ReadLine(std::string* line, std::size_t max_bytes, Deadline deadline) {
  char chunk[4096];
  for (;;) {
    const std::size_t end = buffer_.find('\n');
    if (end != std::string::npos) {
      line->assign(buffer_, 0, end);
      buffer_.erase(0, end + 1);
      return ReadStatus::kOk;
    }
    if (buffer_.size() > max_bytes) return ReadStatus::kTooLong;
    bool exited = false;
    bool readable = false;
    if (!WaitFor(stdout_fd_, POLLIN, deadline, &exited, &readable)) return ReadStatus::kTimeout;
    // A child that exited with nothing more to read has said all it will, even if a grandchild
    // still holds its stdout open (a blocking read would wait for that grandchild).
    const ssize_t n = readable ? ::read(stdout_fd_, static_cast<char*>(chunk), sizeof chunk) : 0;
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *line = buffer_;
      buffer_.clear();
      return ReadStatus::kEof;
    }
    buffer_.append(static_cast<const char*>(chunk), static_cast<std::size_t>(n));
  }
}

ReadStatus Subprocess::ReadToEnd(std::string* out, std::size_t max_bytes, Deadline deadline) {
  char chunk[8192];
  out->swap(buffer_);
  buffer_.clear();
  for (;;) {
    if (out->size() > max_bytes) return ReadStatus::kTooLong;
    bool exited = false;
    bool readable = false;
    if (!WaitFor(stdout_fd_, POLLIN, deadline, &exited, &readable)) return ReadStatus::kTimeout;
    if (exited && !group_killed_) {
      // The child is a zombie until reaped, so its pid (= the group id) cannot have been reused:
      // killing the group now reaches exactly the grandchildren it left behind, and with them
      // every holder of the pipe: end of file follows.
      ::kill(-pid_, SIGKILL);
      group_killed_ = true;
    }
    if (!readable) continue;
    const ssize_t n = ::read(stdout_fd_, static_cast<char*>(chunk), sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) continue;
    if (n <= 0) return ReadStatus::kOk;
    out->append(static_cast<const char*>(chunk), static_cast<std::size_t>(n));
  }
}

std::optional<ExitStatus> Subprocess::Wait(Deadline deadline) {
  if (reaped_) return status_;
  // Its stderr is drained meanwhile: a child blocked writing to a full pipe would never exit.
  bool exited = false;
  bool ready = false;
  if (!WaitFor(-1, 0, deadline, &exited, &ready)) return std::nullopt;
  if (!group_killed_) {
    ::kill(-pid_, SIGKILL);  // the leader is a zombie: see ReadToEnd
    group_killed_ = true;
  }
  return Reap();
}

ExitStatus Subprocess::Kill() {
  if (reaped_) return status_;
  ::kill(-pid_, SIGKILL);
  group_killed_ = true;
  return Reap();
}

ExitStatus Subprocess::Reap() {
  int raw = 0;
  pid_t r = 0;
  do {
    r = ::waitpid(pid_, &raw, 0);
  } while (r < 0 && errno == EINTR);
  reaped_ = true;
  // The group is dead: what its stderr pipe still holds is the end of what it wrote.
  DrainStderr();
  CloseStderr();
  if (r == pid_) {
    if (WIFSIGNALED(raw)) {
      status_.signal = WTERMSIG(raw);
    } else if (WIFEXITED(raw)) {
      status_.code = WEXITSTATUS(raw);
    }
  }
  CloseFd(stdin_fd_);
  return status_;
}

}  // namespace combabc
