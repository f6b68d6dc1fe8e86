// Running the scripts of scripts/report/ (the report, the NetCDF export) with Debian's python.
#include "services/adapters/python_script.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>

#include "combabc/core/install_paths.hpp"

extern char** environ;

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

// The most of a script's stderr kept: its message is the last line.
constexpr std::size_t kMaxScriptStderrBytes = std::size_t{64} << 10;
// How long a script interrupted by SIGINT gets to stop (on KeyboardInterrupt; what it wrote is in
// a staging folder the caller removes) before its process group is killed.
constexpr std::chrono::seconds kInterruptGrace{5};

std::atomic<int> interrupt_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void RecordInterrupt(int signal_number) { interrupt_signal.store(signal_number); }

// While a script runs, SIGINT and SIGTERM (unless ignored) are recorded instead of taking their
// course at once: the script is interrupted and waited for first, so that it never publishes
// after combabc is gone. The previous handlers come back when the guard goes.
class InterruptGuard {
 public:
  InterruptGuard() {
    interrupt_signal.store(0);
    struct sigaction action = {};
    action.sa_handler = RecordInterrupt;
    sigemptyset(&action.sa_mask);
    for (std::size_t k = 0; k < 2; ++k) {
      ::sigaction(kSignals[k], nullptr, &old_[k]);
      installed_[k] = old_[k].sa_handler != SIG_IGN;
      if (installed_[k]) ::sigaction(kSignals[k], &action, nullptr);
    }
  }
  ~InterruptGuard() {
    for (std::size_t k = 0; k < 2; ++k) {
      if (installed_[k]) ::sigaction(kSignals[k], &old_[k], nullptr);
    }
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static int signal() { return interrupt_signal.load(); }

 private:
  static constexpr int kSignals[2] = {SIGINT, SIGTERM};
  struct sigaction old_[2] = {};
  bool installed_[2] = {false, false};
};

}  // namespace

PythonScript FindPythonScript(const std::string& file_name,
                              const char* override_variable,
                              const std::string& needs) {
  PythonScript tools;
  const char* python = std::getenv("COMBABC_PYTHON");
  tools.python = python && *python ? python : "/usr/bin/python3";
  if (::access(tools.python.c_str(), X_OK) != 0) {
    throw Error(ErrorKind::kCantCreate, tools.python + " not found or not executable; " + needs);
  }
  if (const char* env = std::getenv(override_variable); env && *env) {
    tools.script = env;
    if (!fs::is_regular_file(tools.script)) {
      throw Error(ErrorKind::kCantCreate,
                  "script not found (" + std::string(override_variable) + ")",
                  tools.script);
    }
    return tools;
  }
  // Every script lives beside the report's: scripts/report/ in the source tree, installed to
  // share/combabc/report/, found relative to the binary (core/install_paths.hpp).
  const auto candidates = DataFileCandidates("report/" + file_name, "scripts/report/" + file_name);
  tools.script = FindDataFile(candidates).string();
  if (tools.script.empty()) {
    throw Error(ErrorKind::kCantCreate,
                "script " + file_name + " not found at " + DescribeCandidates(candidates) +
                    "; set " + override_variable + " to its path");
  }
  return tools;
}

std::string ModulesProblem(const std::string& python, const std::vector<std::string>& modules) {
  // Imported, not only looked up: a broken installation fails here rather than after sampling.
  // The last line says how it went; only a python that ran the check to its end prints "ok" (any
  // program that merely exits 0, or a python that fails to start, is no such python).
  std::vector<std::string> args = {
      python,
      "-c",
      "import importlib, sys\n"
      "missing, broken = [], []\n"
      "for m in sys.argv[1:]:\n"
      "    try:\n"
      "        importlib.import_module(m)\n"
      "    except ModuleNotFoundError as e:\n"
      "        (missing if e.name == m else broken).append((m, e))\n"
      "    except Exception as e:\n"
      "        broken.append((m, e))\n"
      "if missing:\n"
      "    sys.stderr.write('\\nhas no module ' + missing[0][0] +\n"
      "                     (' (nor ' + missing[1][0] + ')' if len(missing) > 1 else ''))\n"
      "elif broken:\n"
      "    m, e = broken[0]\n"
      "    sys.stderr.write('\\ncannot import ' + m + ' (' + type(e).__name__ + ': ' +\n"
      "                     ' '.join(str(e).split())[:160] + ')')\n"
      "else:\n"
      "    sys.stderr.write('\\nok')\n"};
  args.insert(args.end(), modules.begin(), modules.end());
  const ProcessResult result = RunProcess(args, "");
  const std::size_t last = result.err.find_last_of('\n');
  std::string line = last == std::string::npos ? "" : result.err.substr(last + 1);
  if (result.status == 0 && line == "ok") return {};
  if (line.rfind("has no module ", 0) == 0 || line.rfind("cannot import ", 0) == 0) return line;
  return "did not run the check for " + modules.front() + " (" +
         (result.status >= 128 ? "killed by signal " + std::to_string(result.status - 128)
                               : "exit status " + std::to_string(result.status)) +
         (result.status == 0 ? ", no answer" : "") + ")";
}

ErrorKind KindOfScriptStatus(int status) {
  switch (status) {
    case 64:
      return ErrorKind::kUsage;
    case 65:
      return ErrorKind::kData;
    case 66:
      return ErrorKind::kNoInput;
    case 69:  // EX_UNAVAILABLE: a Python package missing
    case 73:
      return ErrorKind::kCantCreate;
    case 74:
      return ErrorKind::kIo;
    default:
      return ErrorKind::kSoftware;
  }
}

std::string ScriptMessage(const std::string& err, int status, const std::string& prefix) {
  std::string line;
  std::size_t end = err.find_last_not_of("\n\r ");
  if (end != std::string::npos) {
    const std::size_t begin = err.find_last_of('\n', end);
    line = err.substr(begin == std::string::npos ? 0 : begin + 1, end + 1 - (begin + 1));
  }
  const std::string head = prefix + ": ";
  if (line.rfind(head, 0) == 0) line.erase(0, head.size());
  if (line.empty()) line = prefix + " failed with status " + std::to_string(status);
  return line;
}

ProcessResult RunProcess(std::vector<std::string> args,
                         const std::string& needs,
                         const std::function<void()>& before_signal,
                         const std::function<bool(const std::string&)>& on_line) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw Error(ErrorKind::kSoftware, "pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 2);
  // A process group of its own: Ctrl-C at the terminal reaches combabc alone, which interrupts the
  // script and waits for it (below); default signal dispositions.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults;
  sigset_t empty;
  sigfillset(&defaults);
  sigemptyset(&empty);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setsigmask(&attr, &empty);
  posix_spawnattr_setpgroup(&attr, 0);
  posix_spawnattr_setflags(
      &attr,
      static_cast<short>(POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK));
  // Before the spawn: no signal may end combabc while the script is alive.
  std::optional<InterruptGuard> guard(std::in_place);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(pipe_fds[1]);
  if (spawned != 0) {
    ::close(pipe_fds[0]);
    throw Error(ErrorKind::kCantCreate,
                "cannot start " + args[0] + " (" + std::strerror(spawned) + "); " + needs);
  }
  ProcessResult result;
  // Interrupted: SIGINT to the script's group (Python cleans up on KeyboardInterrupt), SIGKILL
  // after kInterruptGrace.
  bool interrupted = false;
  bool killed = false;
  std::chrono::steady_clock::time_point kill_at;
  auto forward_interrupt = [&] {
    if (InterruptGuard::signal() == 0 || killed) return;
    if (!interrupted) {
      interrupted = true;
      ::kill(-pid, SIGINT);
      kill_at = std::chrono::steady_clock::now() + kInterruptGrace;
    } else if (std::chrono::steady_clock::now() >= kill_at) {
      killed = true;
      ::kill(-pid, SIGKILL);
    }
  };
  char buffer[4096];
  std::string pending;  // with on_line: the start of a line not yet ended
  const auto keep = [&](const char* text, std::size_t size) {
    result.err.append(text, size);
    // Only the end is kept: the script's message is its last line.
    if (result.err.size() > 2 * kMaxScriptStderrBytes) {
      result.err.erase(0, result.err.size() - kMaxScriptStderrBytes);
    }
  };
  for (;;) {
    forward_interrupt();
    pollfd p{pipe_fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, 100);  // ms: how soon an interrupt is forwarded
    if (ready <= 0) continue;              // timeout or EINTR: check for an interrupt again
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    if (!on_line) {
      keep(buffer, static_cast<std::size_t>(n));
      continue;
    }
    pending.append(buffer, static_cast<std::size_t>(n));
    std::size_t start = 0;
    for (std::size_t end; (end = pending.find('\n', start)) != std::string::npos; start = end + 1) {
      const std::string line = pending.substr(start, end - start);
      if (!on_line(line)) keep(pending.data() + start, end + 1 - start);
    }
    pending.erase(0, start);
    // A line longer than the kept end is no progress line: kept as it comes.
    if (pending.size() > kMaxScriptStderrBytes) {
      keep(pending.data(), pending.size());
      pending.clear();
    }
  }
  keep(pending.data(), pending.size());
  ::close(pipe_fds[0]);
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, interrupted && !killed ? WNOHANG : 0);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw Error(ErrorKind::kSoftware, "waitpid failed");
    forward_interrupt();
    if (r == 0) ::usleep(20000);
  }
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (const int signal_number = InterruptGuard::signal(); signal_number != 0) {
    // The script is gone; the signal now takes the course it would have taken (for the CLI:
    // ending combabc by it, exit status 130 for SIGINT). A handler that returns gets an error.
    guard.reset();
    if (before_signal) before_signal();
    ::raise(signal_number);
    throw Error(ErrorKind::kSoftware, "interrupted (the script was stopped)");
  }
  return result;
}

}  // namespace combabc::services
