// The non-sampling jobs: simulate one configuration, write the report, export a history.
#include <spawn.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "combabc/core/error.hpp"
#include "combabc/io/export.hpp"
#include "combabc/io/history_store.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/services/calibration.hpp"

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

std::string Sibling(const std::string& history_path, const std::string& name) {
  const auto parent = fs::path(history_path).parent_path();
  return (parent.empty() ? fs::path(name) : parent / name).string();
}

// The plotting script: $COMBABC_REPORT_SCRIPT, else the source tree's, else the installed one.
std::string ReportScript() {
  if (const char* env = std::getenv("COMBABC_REPORT_SCRIPT"); env && *env) return env;
  for (const char* candidate : {COMBABC_REPORT_SCRIPT_SOURCE, COMBABC_REPORT_SCRIPT_INSTALLED}) {
    if (*candidate && fs::exists(candidate)) return candidate;
  }
  throw Error(ErrorKind::kSoftware,
              "report script combabc_report.py not found; set COMBABC_REPORT_SCRIPT");
}

int RunProcess(std::vector<std::string> args) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    throw Error(ErrorKind::kSoftware, "cannot start " + args[0]);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) throw Error(ErrorKind::kSoftware, "waitpid failed");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

void SimulateConfiguration(const std::string& config_path,
                           const std::string& clamps,
                           const std::string& output_csv) {
  const auto config = LoadConfig(config_path);
  // The raw amplitude in metres; the normalised column is derived below. One precompute only.
  auto options = config.model;
  options.normalise = false;
  const int num_clamps = 2 * options.clamps_per_edge;  // checked before the costly precompute
  if (static_cast<int>(clamps.size()) != num_clamps) {
    throw Error(ErrorKind::kUsage,
                "has " + std::to_string(clamps.size()) + " characters; the model has " +
                    std::to_string(num_clamps) + " clamps (one 0/1 per clamp, 1 = fixed)",
                "",
                0,
                "--clamps");
  }
  std::vector<std::uint8_t> bits(clamps.size());
  for (std::size_t k = 0; k < clamps.size(); ++k) {
    if (clamps[k] != '0' && clamps[k] != '1') {
      throw Error(ErrorKind::kUsage,
                  "character " + std::to_string(k + 1) + " is '" + clamps[k] + "'; must be 0 or 1",
                  "",
                  0,
                  "--clamps");
    }
    bits[k] = clamps[k] == '1';
  }
  const plate::SensorModel raw(options);
  std::vector<double> w(static_cast<std::size_t>(raw.num_outputs()));
  raw.Profile(bits, w);
  double peak = 0.0;
  for (double v : w) peak = std::max(peak, v);

  // Written beside the target and renamed, so a failure leaves no partial CSV.
  const std::string tmp = output_csv + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw Error(ErrorKind::kCantCreate, "cannot write", output_csv);
    out.precision(10);
    out << "position_m,displacement_m,normalised\n";
    for (std::size_t i = 0; i < w.size(); ++i) {
      out << raw.output_positions()[i] << ',' << w[i] << ',' << (peak > 0 ? w[i] / peak : 0.0)
          << '\n';
    }
    if (!out.flush()) {
      fs::remove(tmp);
      throw Error(ErrorKind::kIo, "write failed", output_csv);
    }
  }
  std::error_code ec;
  fs::rename(tmp, output_csv, ec);
  if (ec) {
    fs::remove(tmp);
    throw Error(ErrorKind::kCantCreate, "cannot write: " + ec.message(), output_csv);
  }
}

std::string WriteReport(const std::string& history_path, const std::string& directory) {
  // Opening first gives the usual one-line errors for a missing or foreign file.
  { HistoryStore::Open(history_path, /*read_only=*/true); }
  std::string out = directory.empty() ? Sibling(history_path, "report") : directory;
  const char* python = std::getenv("COMBABC_PYTHON");
  const int rc = RunProcess({python && *python ? python : "/usr/bin/python3",
                             ReportScript(),
                             history_path,
                             "--out",
                             out});
  if (rc != 0) {
    throw Error(
        ErrorKind::kSoftware,
        "report script failed with status " + std::to_string(rc) + " (see its message above)",
        history_path);
  }
  return out;
}

std::string ExportHistory(const std::string& history_path,
                          const std::string& directory,
                          bool overwrite) {
  std::string out = directory.empty() ? Sibling(history_path, "export") : directory;
  ExportOptions options;
  options.overwrite = overwrite;
  ExportRun(history_path, out, options);
  return out;
}

}  // namespace combabc::services
