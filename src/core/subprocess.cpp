#include "combabc/core/subprocess.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
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
  if (options.pipe_stdin &&
      ::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, static_cast<int*>(in)) != 0) {
    throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(errno));
  }
  if (::pipe2(static_cast<int*>(out), O_CLOEXEC) != 0) {
    const int e = errno;
    CloseFd(in[0]);
    CloseFd(in[1]);
    throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(e));
  }
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
  posix_spawn_file_actions_adddup2(&s.actions, out[1], STDOUT_FILENO);
  const std::string err = options.stderr_path.empty() ? "/dev/null" : options.stderr_path;
  posix_spawn_file_actions_addopen(
      &s.actions, STDERR_FILENO, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (!options.working_directory.empty()) {
    posix_spawn_file_actions_addchdir_np(&s.actions, options.working_directory.c_str());
  }
  std::vector<char*> argv;
  argv.reserve(options.argv.size() + 1);
  for (const std::string& a : options.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const int rc = ::posix_spawnp(&pid_, argv[0], &s.actions, &s.attr, argv.data(), environ);
  CloseFd(in[1]);
  CloseFd(out[1]);
  if (rc != 0) {
    CloseFd(in[0]);
    CloseFd(out[0]);
    pid_ = -1;
    reaped_ = true;
    throw std::runtime_error("cannot start " + options.argv.front() + ": " + std::strerror(rc));
  }
  stdin_fd_ = in[0];
  stdout_fd_ = out[0];
  pidfd_ = static_cast<int>(::syscall(SYS_pidfd_open, pid_, 0));
  if (pidfd_ < 0) {
    const int e = errno;
    Kill();
    throw std::runtime_error(std::string("cannot watch the child process: ") + std::strerror(e));
  }
}

Subprocess::~Subprocess() {
  if (!reaped_) Kill();
  CloseFd(stdin_fd_);
  CloseFd(stdout_fd_);
  CloseFd(pidfd_);
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
      pollfd p{stdin_fd_, POLLOUT, 0};
      const int r = ::poll(&p, 1, RemainingMs(deadline));
      if (r == 0) {
        timed_out_ = true;
        return false;
      }
      continue;
    }
    return false;  // EPIPE, ECONNRESET: the child closed its stdin or died
  }
  return true;
}

void Subprocess::CloseInput() { CloseFd(stdin_fd_); }

bool Subprocess::WaitReadable(int fd, Deadline deadline, bool* exited, bool* readable) {
  pollfd p[2] = {{fd, POLLIN, 0}, {pidfd_, POLLIN, 0}};
  // Once the exit was seen and the group killed, only the pipe is worth waiting for.
  const nfds_t n = group_killed_ ? 1 : 2;
  if (group_killed_) *exited = true;
  for (;;) {
    const int r = ::poll(static_cast<pollfd*>(p), n, RemainingMs(deadline));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) {
      timed_out_ = true;
      return false;
    }
    if ((p[1].revents & POLLIN) != 0) *exited = true;
    *readable = p[0].revents != 0;  // data, end of file or an error: read() will not block
    return true;
  }
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
    if (!WaitReadable(stdout_fd_, deadline, &exited, &readable)) return ReadStatus::kTimeout;
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
    if (!WaitReadable(stdout_fd_, deadline, &exited, &readable)) return ReadStatus::kTimeout;
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
  pollfd p{pidfd_, POLLIN, 0};
  for (;;) {
    const int r = ::poll(&p, 1, RemainingMs(deadline));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) {
      timed_out_ = true;
      return std::nullopt;
    }
    break;
  }
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
