#pragma once
// The Python scripts combabc runs (scripts/report/: the report, the NetCDF export): where the
// interpreter and a script are, running one, and turning its failure into one combabc::Error line.
#include <functional>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"

namespace combabc::services {

struct PythonScript {
  std::string python;
  std::string script;
};

// $COMBABC_PYTHON, else /usr/bin/python3 (Debian's, which has the packages; not a pyenv shim),
// and the script `file_name` of scripts/report/: $<override_variable> when that is set, else the
// installed one of the install that runs (share/combabc/report/, found relative to the binary:
// core/install_paths.hpp), or for a build-tree binary the source tree's. `needs` says what to
// install (the message when the python is missing). Error kCantCreate when either is missing.
PythonScript FindPythonScript(const std::string& file_name,
                              const char* override_variable,
                              const std::string& needs);

struct ProcessResult {
  int status = 0;   // the exit status, or 128 + the signal that ended it
  std::string err;  // what the process wrote on stderr: its last kMaxStderrBytes (64 KiB)
};

// Runs args[0] (a path, not looked up in PATH) through core's Subprocess: in a process group of
// its own, stdin and stdout /dev/null, stderr captured; what is left of the group is killed when
// it ends. kCantCreate "cannot start <args[0]> (<reason>); <needs>" when it cannot start. A SIGINT
// or SIGTERM that arrives meanwhile (not ignored) is held (SignalHold) and interrupts the script
// (SIGINT to its group, SIGKILL 5 s later), which is reaped; then `before_signal` runs (the report
// removes its staging folder there: the signal may end combabc without unwinding), the signal takes
// its course with combabc's own handlers (for the CLI: combabc ends by it), and if that handler
// returns, Error(kSoftware) "interrupted". `on_line`, when set, hears each line of stderr (without
// its newline) as it comes; a line it returns true for was a progress line and is not kept in
// `err`.
ProcessResult RunProcess(std::vector<std::string> args,
                         const std::string& needs,
                         const std::function<void()>& before_signal = {},
                         const std::function<bool(const std::string&)>& on_line = {});

// Why `python` cannot serve a script that imports `modules`: "has no module numpy (nor
// matplotlib)", "cannot import numpy (<error>)", or, for a program that did not run the check to
// its end (not a python, a python that does not start), "did not run the check for numpy (exit
// status 1)". Empty when it imports them all (one interpreter start that imports them).
std::string ModulesProblem(const std::string& python, const std::vector<std::string>& modules);

// The scripts exit with the sysexits code of what went wrong.
ErrorKind KindOfScriptStatus(int status);

// The script's own one-line message: its last line on stderr without the "<prefix>: " it starts
// with, so that a failed script is one combabc error line.
std::string ScriptMessage(const std::string& err, int status, const std::string& prefix);

}  // namespace combabc::services
