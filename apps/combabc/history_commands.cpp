// The commands that read a run's history: `combabc report`, `combabc export`, `combabc verify`.
#include <iostream>
#include <memory>
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/services/history_tools.hpp"
#include "combabc/services/report.hpp"
#include "subcommands.hpp"

namespace combabc::cli {
namespace {

constexpr const char* kOverwriteDir =
    "Write into DIR even if combabc did not create it (replaces only same-named files)";

// report and export: a history, and the directory they write.
struct OutputArgs {
  std::string history;
  std::string directory;
  bool overwrite = false;
};

struct ExportArgs : OutputArgs {
  bool no_netcdf = false;
  bool all_waves = false;
};

int ReportCommand(const OutputArgs& args, const Session& session) {
  return PrimaryOnly(session, [&] {
    // Written first, printed after: a failure prints no half line on stdout.
    const auto directory =
        services::WriteReport(args.history,
                              args.directory,
                              args.overwrite,
                              ReportProgressLine(session, false, /*off_terminal=*/false));
    std::cout << "report: " << directory << "/index.html\n";
    return 0;
  });
}

int ExportCommand(const ExportArgs& args, const Session& session) {
  return PrimaryOnly(session, [&] {
    const auto outcome = services::ExportHistory(
        args.history, args.directory, args.overwrite, !args.no_netcdf, args.all_waves);
    std::cout << "export: " << outcome.directory << "\n";
    if (!outcome.note.empty()) std::cerr << "combabc: note: " << outcome.note << "\n";
    return 0;
  });
}

int VerifyCommand(const std::string& history, const Session& session) {
  return PrimaryOnly(session, [&] {
    const auto outcome = services::VerifyHistory(history);
    for (const std::string& line : outcome.lines) {
      (outcome.ok ? std::cout : std::cerr)
          << (outcome.ok ? "" : "combabc: data error: ") << line << "\n";
    }
    return outcome.ok ? 0 : ExitCode(ErrorKind::kData);
  });
}

}  // namespace

Command AddReportCommand(CLI::App& app) {
  auto args = std::make_shared<OutputArgs>();
  auto* report = app.add_subcommand(
      "report", "Write figures ([output] figures: png, svg, pdf) and index.html of a run");
  report->add_option("RUN.sqlite", args->history, "History file of the run")->required();
  report->add_option(
      "-o,--output", args->directory, "Directory (default: report/ beside the history)");
  report->add_flag("--overwrite", args->overwrite, kOverwriteDir);
  return {report, [args](const Session& session) { return ReportCommand(*args, session); }};
}

Command AddExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  auto* exporter = app.add_subcommand("export", "Export a run to CSV and JSON (pandas, MATLAB)");
  exporter->add_option("RUN.sqlite", args->history, "History file of the run")->required();
  exporter->add_option(
      "-o,--output", args->directory, "Directory (default: export/ beside the history)");
  exporter->add_flag("--overwrite", args->overwrite, kOverwriteDir);
  exporter->add_flag("--no-netcdf",
                     args->no_netcdf,
                     "Skip inference_data.nc (ArviZ layout; needs python3-xarray)");
  exporter->add_flag("--all-waves",
                     args->all_waves,
                     "inference_data.nc: also every wave's resampled posterior "
                     "(groups posterior_wave_<k>, sample_stats_wave_<k>)");
  return {exporter, [args](const Session& session) { return ExportCommand(*args, session); }};
}

Command AddVerifyCommand(CLI::App& app) {
  auto history = std::make_shared<std::string>();
  auto* verify = app.add_subcommand(
      "verify", "Check a history's integrity (structure, checksums); exit 0 if sound, 65 if not");
  verify->add_option("RUN.sqlite", *history, "History file of the run")->required();
  return {verify, [history](const Session& session) { return VerifyCommand(*history, session); }};
}

}  // namespace combabc::cli
