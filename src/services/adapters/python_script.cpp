// Running the scripts of scripts/report/ (the report, the NetCDF export) with Debian's python.
#include "services/adapters/python_script.hpp"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "combabc/core/install_paths.hpp"
#include "combabc/core/subprocess.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

// How long a script interrupted by SIGINT gets to stop (on KeyboardInterrupt; what it wrote is in
// a staging folder the caller removes) before its process group is killed.
constexpr std::chrono::seconds kInterruptGrace{5};

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
  SubprocessOptions options;
  options.argv = std::move(args);
  options.search_path = false;  // the python FindPythonScript checked, not one in PATH
  options.pipe_stdout = false;
  options.capture_stderr = true;  // the script's message is its last line
  options.on_stderr_line = on_line;
  // Before the spawn: no signal may end combabc while the script is alive.
  SignalHold hold;
  std::optional<Subprocess> script;
  try {
    script.emplace(options);
  } catch (const SpawnError& e) {
    throw Error(
        ErrorKind::kCantCreate,
        "cannot start " + options.argv.front() + " (" + std::strerror(e.error()) + "); " + needs);
  } catch (const std::runtime_error& e) {
    throw Error(ErrorKind::kSoftware, e.what());
  }
  const ExitStatus status = script->WaitForwarding(hold, kInterruptGrace);
  ProcessResult result{status.signal != 0 ? 128 + status.signal : status.code, script->Stderr()};
  if (const int signal_number = hold.signal(); signal_number != 0) {
    // The script is gone; the signal now takes the course it would have taken (for the CLI:
    // ending combabc by it, exit status 130 for SIGINT). A handler that returns gets an error.
    hold.Release();
    if (before_signal) before_signal();
    ::raise(signal_number);
    throw Error(ErrorKind::kSoftware, "interrupted (the script was stopped)");
  }
  return result;
}

}  // namespace combabc::services
