// `combabc enumerate`.
#include <iostream>
#include <limits>
#include <memory>

#include "combabc/services/enumerate.hpp"
#include "interrupt.hpp"
#include "model_choice_command.hpp"
#include "subcommands.hpp"

namespace combabc::cli {
namespace {

struct EnumerateArgs {
  services::EnumerateRequest request;
  bool no_report = false;
  bool quiet = false;
};

int EnumerateCommand(EnumerateArgs& args, const Session& session) {
  services::EnumerateRequest& request = args.request;
  request.executor = session.executor();
  if (session.primary() && session.under_mpirun()) {
    SetTermNote(
        "combabc: SIGTERM from mpirun (a rank died, or the job was stopped): the enumeration "
        "ends; nothing is written (an enumeration cannot be resumed)\n");
  }
  request.report = !args.no_report;
  request.on_report_progress = ReportProgressLine(session, args.quiet);
  if (IsModelChoiceConfig(request.config_path)) {
    return EnumerateModelChoiceCommand(request, args.quiet, session);
  }
  const std::vector<bool> temperatures = TemperatureSlotsOfConfig(request.config_path);
  return Guarded(session, args.quiet, temperatures, [&](SmcObserver* observer) {
    const auto outcome = services::RunEnumeration(request, observer);
    if (outcome.interrupted) {
      std::cerr << "interrupted after " << outcome.enumerated << " of " << outcome.configurations
                << " configurations; nothing written (an enumeration cannot be resumed)\n";
      return kExitInterrupted;
    }
    // The fit and sanity checks: warnings, on stderr, never an error.
    std::cerr << FormatFitChecks(outcome.checks, "m");
    std::cout << "enumerated " << outcome.configurations << " configurations: " << outcome.accepted
              << " accepted, evidence " << outcome.evidence << " (" << outcome.wall_seconds
              << " s)\n";
    if (outcome.low_fidelity_ignored) {
      std::cout << "(the expensive simulator's exact posterior: [simulator.low_fidelity] is not "
                   "used)\n";
    }
    std::cout << "history: " << outcome.history_path << "\n"
              << "tables:  " << outcome.enumeration_directory << "\n";
    if (!outcome.report_directory.empty()) {
      std::cout << "report:  " << outcome.report_directory << "/index.html\n";
    }
    PrintAnswer(session, args.quiet, outcome.answer, outcome.strip);
    return 0;
  });
}

}  // namespace

Command AddEnumerateCommand(CLI::App& app) {
  auto args = std::make_shared<EnumerateArgs>();
  services::EnumerateRequest& request = args->request;
  auto* enumerate = app.add_subcommand(
      "enumerate", "Exact ABC posterior by simulating every configuration of the free bits");
  enumerate->add_option("CONFIG", request.config_path, "Config file")->required();
  enumerate
      ->add_option("--threshold",
                   request.thresholds,
                   "One per threshold component (default: the config's final thresholds)")
      ->check(RealIn(0.0, std::numeric_limits<double>::infinity()));
  enumerate->add_option("-o,--output",
                        request.output_directory,
                        "Folder of its history, tables and report (default: enumeration/ in the "
                        "[output] directory, apart from run's)");
  enumerate
      ->add_option("-j,--threads", request.threads, "Threads, 0 = all cores (overrides [sampler])")
      ->check(CLI::Range(0, kMaxThreads));
  enumerate->add_flag(
      "--overwrite", request.overwrite, "Replace an existing history and its files");
  enumerate->add_option("--top", request.top, "Configurations in top_configurations.csv")
      ->check(CLI::Range(1, 1000000));
  enumerate->add_flag("--no-report", args->no_report, "Do not write figures at the end");
  enumerate->add_flag("-q,--quiet", args->quiet, "No progress display, no answer at the end");
  AddNoCacheFlag(*enumerate);
  return {enumerate, [args](const Session& session) { return EnumerateCommand(*args, session); }};
}

}  // namespace combabc::cli
