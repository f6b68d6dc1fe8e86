// combabc: the command-line front end. Thin by design: parsing, progress display and exit codes
// here; every job is a call into combabc::services.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>

#include "combabc/core/error.hpp"
#include "combabc/services/calibration.hpp"
#include "progress_display.hpp"

namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void OnSigint(int) { g_interrupted = true; }

// sysexits.h codes for failures that are not combabc::Error.
constexpr int kExitUsage = 64;
constexpr int kExitSoftware = 70;

void PrintOutcome(const combabc::services::RunOutcome& outcome) {
  std::cout << outcome.history.summary.BriefReport() << "\n"
            << "history: " << outcome.history_path << "\n";
  if (!outcome.report_directory.empty()) {
    std::cout << "report:  " << outcome.report_directory << "/index.html\n";
  }
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"combabc " COMBABC_VERSION
               " - combinatorial ABC-SMC calibration of binary (on/off) simulator parameters"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "combabc " COMBABC_VERSION);

  combabc::services::RunRequest request;
  bool quiet = false, no_report = false;
  auto* run = app.add_subcommand("run", "Run a calibration from a TOML config (docs/config.md)");
  run->add_option("CONFIG", request.config_path, "Config file")->required();
  run->add_option("-o,--output", request.output_directory, "Output directory (overrides [output])");
  run->add_option("-j,--threads", request.threads, "Threads (overrides [sampler] threads)");
  run->add_flag("--overwrite", request.overwrite, "Replace an existing history file");
  run->add_flag("--no-report", no_report, "Do not write figures at the end");
  run->add_flag("-q,--quiet", quiet, "No progress display");

  std::string history;
  int resume_threads = -1;
  auto* resume = app.add_subcommand("resume", "Continue a killed or interrupted run");
  resume->add_option("RUN_DB", history, "History file of the run")->required();
  resume->add_option("-j,--threads", resume_threads, "Threads (default: the run's own)");
  resume->add_flag("--no-report", no_report, "Do not write figures at the end");
  resume->add_flag("-q,--quiet", quiet, "No progress display");

  std::string sim_config, clamps, sim_out = "profile.csv";
  auto* simulate = app.add_subcommand("simulate", "Simulate one clamp configuration to CSV");
  simulate->add_option("CONFIG", sim_config, "Config file (its [model] is used)")->required();
  simulate->add_option("--clamps", clamps, "One 0/1 per clamp, 1 = fixed, e.g. 0110...")
      ->required();
  simulate->add_option("-o,--output", sim_out, "CSV to write (default profile.csv)");

  std::string out_dir;
  bool overwrite_export = false;
  auto* report = app.add_subcommand("report", "Write figures (PNG, SVG) and index.html of a run");
  report->add_option("RUN_DB", history, "History file of the run")->required();
  report->add_option("-o,--output", out_dir, "Directory (default: report/ beside the history)");

  auto* exporter = app.add_subcommand("export", "Export a run to CSV and JSON (pandas, MATLAB)");
  exporter->add_option("RUN_DB", history, "History file of the run")->required();
  exporter->add_option("-o,--output", out_dir, "Directory (default: export/ beside the history)");
  exporter->add_flag("--overwrite", overwrite_export, "Replace an existing export directory");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line, like every other error; the full usage is one --help away.
    std::cerr << "combabc: usage error: " << e.what() << " (see combabc --help)\n";
    return kExitUsage;
  }

  std::signal(SIGINT, OnSigint);
  std::signal(SIGTERM, OnSigint);
  combabc::cli::ProgressDisplay progress(&g_interrupted, isatty(STDERR_FILENO) != 0);
  combabc::SmcObserver* observer = quiet ? nullptr : &progress;
  try {
    if (*run) {
      request.report = !no_report;
      PrintOutcome(combabc::services::RunCalibration(request, observer));
      if (g_interrupted) std::cerr << "interrupted; continue with: combabc resume <RUN_DB>\n";
    } else if (*resume) {
      PrintOutcome(
          combabc::services::ResumeCalibration(history, resume_threads, !no_report, observer));
    } else if (*simulate) {
      combabc::services::SimulateConfiguration(sim_config, clamps, sim_out);
      std::cout << "wrote " << sim_out << "\n";
    } else if (*report) {
      std::cout << "report: " << combabc::services::WriteReport(history, out_dir)
                << "/index.html\n";
    } else if (*exporter) {
      std::cout << "export: "
                << combabc::services::ExportHistory(history, out_dir, overwrite_export) << "\n";
    }
  } catch (const combabc::Error& e) {
    progress.Clear();
    std::cerr << "combabc: " << ToString(e.kind()) << ": " << e.what() << "\n";
    return combabc::ExitCode(e.kind());
  } catch (const std::exception& e) {
    progress.Clear();
    std::cerr << "combabc: internal error: " << e.what() << "\n";
    return kExitSoftware;
  }
  return g_interrupted ? 130 : 0;
} catch (const std::exception& e) {
  // Setting up the command line (CLI11, the progress display) can throw too: exit 70, no abort.
  std::cerr << "combabc: internal error: " << e.what() << "\n";
  return kExitSoftware;
} catch (...) {
  std::cerr << "combabc: internal error: unknown exception\n";
  return kExitSoftware;
}
