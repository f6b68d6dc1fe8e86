// The report: runs scripts/report/combabc_report.py on a history and turns its failure into one
// combabc::Error line. The script itself applies the output-directory rules of OutputDirectory.
#include <cstdlib>
#include <filesystem>

#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/services/report.hpp"
#include "services/python_script.hpp"
#include "services/report_checks.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

constexpr const char* kReportNeeds =
    "the report needs Python 3 with numpy and matplotlib (Debian: apt-get install python3 "
    "python3-numpy python3-matplotlib), or COMBABC_PYTHON naming such a python";

PythonScript FindReportTools() {
  try {
    return FindPythonScript("combabc_report.py", "COMBABC_REPORT_SCRIPT", kReportNeeds);
  } catch (const Error& e) {
    throw Error(e.kind(), "report: " + e.message(), e.file());
  }
}

}  // namespace

std::string ReportDirectory(const std::string& history_path) {
  const auto parent = fs::path(history_path).parent_path();
  return (parent.empty() ? fs::path("report") : parent / "report").string();
}

void CheckReportPossible(const std::string& directory) {
  const PythonScript tools = FindReportTools();
  // A python without the plotting packages would be found out only after sampling: said now.
  if (const auto missing = MissingModules(tools.python, {"numpy", "matplotlib"});
      !missing.empty()) {
    const char* variable = std::getenv("COMBABC_PYTHON");
    const std::string which = variable != nullptr && *variable != '\0'
                                  ? "COMBABC_PYTHON=" + tools.python
                                  : tools.python + " (COMBABC_PYTHON unset)";
    throw Error(ErrorKind::kCantCreate,
                "report: " + which + " has no module " + missing.front() +
                    (missing.size() > 1 ? " (nor " + missing[1] + ")" : "") + "; " + kReportNeeds +
                    "; or use --no-report");
  }
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
  const PythonScript tools = FindReportTools();
  std::vector<std::string> args = {tools.python, tools.script, "--out", out};
  if (overwrite) args.push_back("--overwrite");
  // "--": a history file whose name starts with '-' is still the history.
  args.insert(args.end(), {"--", history_path});
  ProcessResult result;
  try {
    result = RunProcess(args, kReportNeeds);
  } catch (const Error& e) {
    throw Error(e.kind(), "report: " + e.message(), e.file());
  }
  if (result.status != 0) {
    throw Error(KindOfScriptStatus(result.status),
                ScriptMessage(result.err, result.status, "combabc_report"));
  }
  return out;
}

}  // namespace combabc::services
