// The report: runs scripts/report/combabc_report.py on a history and turns its failure into one
// combabc::Error line. The script itself applies the output-directory rules of OutputDirectory.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/services/calibration.hpp"
#include "services/report_checks.hpp"

extern char** environ;

#ifndef COMBABC_REPORT_SCRIPT_SOURCE
#define COMBABC_REPORT_SCRIPT_SOURCE ""
#endif
#ifndef COMBABC_REPORT_SCRIPT_INSTALLED
#define COMBABC_REPORT_SCRIPT_INSTALLED ""
#endif

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

// What the report needs besides the history: a Python with numpy and matplotlib, and the script.
struct ReportTools {
  std::string python;
  std::string script;
};

constexpr const char* kReportNeeds =
    "the report needs Python 3 with numpy and matplotlib (Debian: apt-get install python3 "
    "python3-numpy python3-matplotlib), or COMBABC_PYTHON naming such a python";

// $COMBABC_PYTHON, else /usr/bin/python3 (Debian's, which has the packages; not a pyenv shim).
// The script: $COMBABC_REPORT_SCRIPT, else the source tree's, else the installed one.
ReportTools FindReportTools() {
  ReportTools tools;
  const char* python = std::getenv("COMBABC_PYTHON");
  tools.python = python && *python ? python : "/usr/bin/python3";
  if (::access(tools.python.c_str(), X_OK) != 0) {
    throw Error(ErrorKind::kCantCreate,
                "report: " + tools.python + " not found or not executable; " + kReportNeeds);
  }
  if (const char* env = std::getenv("COMBABC_REPORT_SCRIPT"); env && *env) {
    tools.script = env;
    if (!fs::is_regular_file(tools.script)) {
      throw Error(ErrorKind::kCantCreate, "report script not found (COMBABC_REPORT_SCRIPT)", env);
    }
    return tools;
  }
  for (const char* candidate : {COMBABC_REPORT_SCRIPT_SOURCE, COMBABC_REPORT_SCRIPT_INSTALLED}) {
    if (*candidate && fs::is_regular_file(candidate)) {
      tools.script = candidate;
      return tools;
    }
  }
  throw Error(ErrorKind::kCantCreate,
              "report script combabc_report.py not found; set COMBABC_REPORT_SCRIPT to its path");
}

// The script exits with the sysexits code of what went wrong (scripts/report/combabc_report.py).
ErrorKind KindOfScriptStatus(int status) {
  switch (status) {
    case 64:
      return ErrorKind::kUsage;
    case 65:
      return ErrorKind::kData;
    case 66:
      return ErrorKind::kNoInput;
    case 69:  // EX_UNAVAILABLE: numpy or matplotlib missing
    case 73:
      return ErrorKind::kCantCreate;
    case 74:
      return ErrorKind::kIo;
    default:
      return ErrorKind::kSoftware;
  }
}

// The script's own one-line message (its last line on stderr, without its name), so that a
// failed report is one combabc error line.
std::string ScriptMessage(const std::string& err, int status) {
  std::string line;
  std::size_t end = err.find_last_not_of("\n\r ");
  if (end != std::string::npos) {
    const std::size_t begin = err.find_last_of('\n', end);
    line = err.substr(begin == std::string::npos ? 0 : begin + 1, end + 1 - (begin + 1));
  }
  const std::string prefix = "combabc_report: ";
  if (line.rfind(prefix, 0) == 0) line.erase(0, prefix.size());
  if (line.empty()) line = "report script failed with status " + std::to_string(status);
  return line;
}

struct ProcessResult {
  int status = 0;
  std::string err;  // everything the process wrote on stderr
};

// Runs argv[0] with stdout discarded and stderr captured.
ProcessResult RunProcess(std::vector<std::string> args) {
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
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(pipe_fds[1]);
  if (spawned != 0) {
    ::close(pipe_fds[0]);
    throw Error(
        ErrorKind::kCantCreate,
        "report: cannot start " + args[0] + " (" + std::strerror(spawned) + "); " + kReportNeeds);
  }
  ProcessResult result;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    result.err.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw Error(ErrorKind::kSoftware, "waitpid failed");
  }
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

}  // namespace

std::string ReportDirectory(const std::string& history_path) {
  const auto parent = fs::path(history_path).parent_path();
  return (parent.empty() ? fs::path("report") : parent / "report").string();
}

void CheckReportPossible(const std::string& directory) {
  FindReportTools();
  // A directory whose parent does not exist yet (a new output directory) will be created fresh.
  const fs::path parent = fs::path(directory).parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent.empty() ? fs::path(".") : parent, ec)) return;
  OutputDirectory::Check(directory,
                         /*overwrite=*/false,
                         "the run writes its report there: move it away, or use another output "
                         "directory (-o) or --no-report");
}

std::string WriteReport(const std::string& history_path,
                        const std::string& directory,
                        bool overwrite) {
  // Reading it all first gives the usual one-line errors for a missing, foreign or corrupt file
  // (the script itself trusts what it reads).
  { HistoryStore::Open(history_path, /*read_only=*/true).LoadHistory(); }
  std::string out = directory.empty() ? ReportDirectory(history_path) : directory;
  const ReportTools tools = FindReportTools();
  std::vector<std::string> args = {tools.python, tools.script, "--out", out};
  if (overwrite) args.push_back("--overwrite");
  // "--": a history file whose name starts with '-' is still the history.
  args.insert(args.end(), {"--", history_path});
  const ProcessResult result = RunProcess(args);
  if (result.status != 0) {
    throw Error(KindOfScriptStatus(result.status), ScriptMessage(result.err, result.status));
  }
  return out;
}

}  // namespace combabc::services
