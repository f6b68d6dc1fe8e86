#pragma once
// Runs the combabc CLI as a user would (a child process) and captures its exit code and output.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "support/test_support.hpp"

extern "C" char** environ;

namespace combabc::testing {

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string ReadFile(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Starts `argv` (looked up in PATH) with stdout/stderr redirected to cli.stdout / cli.stderr in
// `dir` (stdout to `stdout_path` instead when given: an existing file such as /dev/full);
// returns the child's pid, or -1.
inline pid_t SpawnWithOutputIn(std::vector<std::string> all,
                               const std::filesystem::path& dir,
                               const std::string& stdout_path = "") {
  std::vector<char*> argv;
  argv.reserve(all.size() + 1);
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string out = (dir / "cli.stdout").string(), err = (dir / "cli.stderr").string();
  if (stdout_path.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  } else {
    posix_spawn_file_actions_addopen(&actions, 1, stdout_path.c_str(), O_WRONLY, 0);
  }
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  if (posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

// Starts the CLI with stdout/stderr redirected to files in `dir`; returns the child's pid.
inline pid_t SpawnCli(const std::vector<std::string>& args, const std::filesystem::path& dir) {
  std::vector<std::string> all = {COMBABC_CLI};
  all.insert(all.end(), args.begin(), args.end());
  return SpawnWithOutputIn(std::move(all), dir);
}

inline CliResult WaitCli(pid_t pid, const std::filesystem::path& dir) {
  CliResult r;
  int status = 0;
  if (pid > 0 && waitpid(pid, &status, 0) == pid) {
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  r.out = ReadFile(dir / "cli.stdout");
  r.err = ReadFile(dir / "cli.stderr");
  return r;
}

inline CliResult RunCli(const std::vector<std::string>& args, const std::filesystem::path& dir) {
  return WaitCli(SpawnCli(args, dir), dir);
}

inline int CountLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace combabc::testing
