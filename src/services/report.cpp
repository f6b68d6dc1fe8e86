// The report: stages the run's export, runs scripts/report/combabc_report.py on it (it draws the
// figures and index.html into a staging folder; a failure is one combabc::Error line) and publishes
// what it drew under the output-directory rules of OutputDirectory.
#include <stdlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string_view>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/export/export.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/services/report.hpp"
#include "services/adapters/python_script.hpp"
#include "services/design_campaign.hpp"
#include "services/steps/read_back.hpp"
#include "services/steps/report_checks.hpp"

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

// A private folder (mode 0700) under the system's temporary directory, removed with everything in
// it when the report is done: the export is staged there and the script draws there.
class StagingFolder {
 public:
  StagingFolder() {
    std::error_code ec;
    const fs::path base = fs::temp_directory_path(ec);
    std::string pattern = ((ec ? fs::path("/tmp") : base) / "combabc-report-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw Error(ErrorKind::kCantCreate,
                  "report: cannot create a staging folder: " + std::string(std::strerror(errno)),
                  pattern);
    }
    path_ = pattern;
  }
  StagingFolder(const StagingFolder&) = delete;
  StagingFolder& operator=(const StagingFolder&) = delete;
  ~StagingFolder() { Remove(); }
  const fs::path& path() const { return path_; }
  // Also called on an interrupt, before the signal ends combabc. Only this object's folder, made
  // by mkdtemp above, is removed.
  void Remove() const {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }

 private:
  fs::path path_;
};

// The script's files into the report directory, all together, under OutputDirectory's rules.
void Publish(const fs::path& drawn, const std::string& out, bool overwrite) {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(drawn, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec)) names.push_back(it->path().filename().string());
  }
  if (ec || names.empty()) {
    throw Error(ErrorKind::kSoftware, "report: the script drew nothing", drawn.string());
  }
  std::sort(names.begin(), names.end());
  OutputDirectory directory(out, overwrite);
  for (const std::string& name : names) {
    std::ifstream in(drawn / name, std::ios::binary);
    const std::string content{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (in.bad()) {
      throw Error(ErrorKind::kIo, "report: cannot read the drawn " + name, (drawn / name).string());
    }
    directory.Add(name).write(content.data(), static_cast<std::streamsize>(content.size()));
  }
  directory.Commit();
}

}  // namespace

std::string ReportDirectory(const std::string& history_path) {
  const auto parent = fs::path(history_path).parent_path();
  return (parent.empty() ? fs::path("report") : parent / "report").string();
}

void CheckReportPossible(const std::string& directory) {
  const PythonScript tools = FindReportTools();
  // A python without the plotting packages (or no python at all) would be found out only after
  // sampling: said now.
  if (const std::string problem = ModulesProblem(tools.python, {"numpy", "matplotlib"});
      !problem.empty()) {
    const char* variable = std::getenv("COMBABC_PYTHON");
    const std::string which = variable != nullptr && *variable != '\0'
                                  ? "COMBABC_PYTHON=" + tools.python
                                  : tools.python + " (COMBABC_PYTHON unset)";
    throw Error(ErrorKind::kCantCreate,
                "report: " + which + " " + problem + "; " + kReportNeeds + "; or use --no-report");
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
                        bool overwrite,
                        const ReportProgress& progress) {
  // The usual one-line errors for a missing, foreign or corrupt history (a corrupt wave: when the
  // export reads it).
  const HistoryStore store = HistoryStore::Open(history_path, /*read_only=*/true);
  std::string out = directory.empty() ? ReportDirectory(history_path) : directory;
  // Refused before any work; the directory itself is made only when the report is published, so
  // that an interrupted report leaves nothing there.
  OutputDirectory::Check(out, overwrite);
  const PythonScript tools = FindReportTools();
  if (progress) progress(0, 0);
  const StagingFolder staging;
  const fs::path exported = staging.path() / "export";
  const fs::path drawn = staging.path() / "report";
  ExportOptions export_options;
  const RunMetadata metadata = store.LoadMetadata();
  export_options.bit_positions = BitPositions(metadata);
  export_options.strip = StripOf(metadata);
  export_options.checks = CheckOptions(metadata);
  // The section "Which experiment decided which clamp" of a joint run of the sensor; without it
  // where it cannot be had (the report draws what the export holds).
  export_options.campaign = RunCampaignView(history_path, nullptr);
  ExportRun(store, exported.string(), export_options);
  std::vector<std::string> args = {tools.python,
                                   tools.script,
                                   "--out",
                                   drawn.string(),
                                   "--history",
                                   fs::absolute(history_path).string()};
  // The script's "combabc_report: progress D/N" lines, one per figure drawn, are heard here and
  // kept out of its message.
  std::function<bool(const std::string&)> on_line;
  if (progress) {
    args.push_back("--progress");
    on_line = [&progress](const std::string& line) {
      constexpr std::string_view kHead = "combabc_report: progress ";
      int done = 0;
      int total = 0;
      if (line.rfind(kHead, 0) != 0 ||
          std::sscanf(line.c_str() + kHead.size(), "%d/%d", &done, &total) != 2) {
        return false;
      }
      progress(done, total);
      return true;
    };
  }
  // "--": the staged export is never an option, whatever TMPDIR is.
  args.push_back("--");
  args.push_back(exported.string());
  ProcessResult result;
  try {
    result = RunProcess(
        args, kReportNeeds, [&] { staging.Remove(); }, on_line);
  } catch (const Error& e) {
    throw Error(e.kind(), "report: " + e.message(), e.file());
  }
  if (result.status != 0) {
    throw Error(KindOfScriptStatus(result.status),
                ScriptMessage(result.err, result.status, "combabc_report"));
  }
  Publish(drawn, out, overwrite);
  return out;
}

}  // namespace combabc::services
