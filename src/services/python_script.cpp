// Running the scripts of scripts/report/ (the report, the NetCDF export) with Debian's python.
#include "services/python_script.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "combabc/core/install_paths.hpp"

extern char** environ;

namespace combabc::services {
namespace fs = std::filesystem;

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

ProcessResult RunProcess(std::vector<std::string> args, const std::string& needs) {
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
    throw Error(ErrorKind::kCantCreate,
                "cannot start " + args[0] + " (" + std::strerror(spawned) + "); " + needs);
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

}  // namespace combabc::services
