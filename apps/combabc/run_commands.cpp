// `combabc run` and `combabc resume`.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "combabc/services/run.hpp"
#include "interrupt.hpp"
#include "model_choice_command.hpp"
#include "subcommands.hpp"

namespace combabc::cli {
namespace {

// A run stopped because too many simulations failed: the simulator, not the calibration, is the
// problem (sysexits EX_UNAVAILABLE). Its finished waves are kept.
constexpr int kExitTooManyFailures = 69;

struct RunArgs {
  services::RunRequest request;
  bool no_report = false;
  bool quiet = false;
};

struct ResumeArgs {
  services::ResumeRequest request;
  // Each sets its limit only when given (its option's count).
  std::int64_t max_simulations = 0;
  double max_wall_time = 0.0;
  double min_acceptance_rate = 0.0;
  double max_failure_fraction = 0.0;
  int waves = 0;
  CLI::Option* max_simulations_option = nullptr;
  CLI::Option* max_wall_time_option = nullptr;
  CLI::Option* min_acceptance_rate_option = nullptr;
  CLI::Option* max_failure_fraction_option = nullptr;
  CLI::Option* waves_option = nullptr;
  bool no_report = false;
  bool quiet = false;
};

// The checks before sampling go to stderr when the first wave ends (after its progress line,
// before the next wave's), once per process: the end prints them only if this process did not see
// the first wave end (a resume after it).
class ChecksPrinter {
 public:
  std::function<void(const FitChecks&)> Callback() {
    return [this](const FitChecks& checks) {
      std::cerr << FormatBeforeChecks(checks, "m") << std::flush;
      before_printed_ = true;
    };
  }
  // The fit and sanity checks at the end: warnings, on stderr, never an error.
  void AtEnd(const FitChecks& checks) const {
    if (!before_printed_) std::cerr << FormatBeforeChecks(checks, "m");
    std::cerr << FormatAfterChecks(checks);
  }

 private:
  bool before_printed_ = false;
};

// A rejection run (no wave moved) stopped on its acceptance floor or its budget after its first
// wave: what resample-move is for (several experiments: docs/algorithm.md, "Resample-move").
bool SlowingRejectionRun(const RunHistory& history, Termination stop) {
  if (stop != Termination::kAcceptanceRateTooLow && stop != Termination::kBudgetExhausted) {
    return false;
  }
  return history.waves.size() >= 2 &&
         std::none_of(history.waves.begin(), history.waves.end(), [](const WaveRecord& w) {
           return w.moves.has_value();
         });
}

void PrintOutcome(const services::RunOutcome& outcome, const ChecksPrinter& checks) {
  const RunSummary& summary = outcome.history.summary;
  checks.AtEnd(outcome.checks);
  std::cout << summary.BriefReport() << "\n";
  std::cout << "history: " << outcome.history_path << "\n";
  if (!outcome.report_directory.empty()) {
    std::cout << "report:  " << outcome.report_directory << "/index.html\n";
  }
  // A run that gave up says why on stderr too, where a user watching the progress looks.
  switch (summary.termination) {
    case Termination::kBudgetExhausted:
    case Termination::kAcceptanceRateTooLow:
    case Termination::kWallTimeExceeded:
    case Termination::kTooManyFailures:
      std::cerr << "stopped: " << summary.message << "\n"
                << "finished waves are kept; to go on, raise the limit: combabc resume "
                << outcome.history_path << " " << services::LimitOption(summary.termination)
                << " ...\n";
      if (SlowingRejectionRun(outcome.history, summary.termination)) {
        std::cerr << "fresh candidates are rarely accepted any more; a sampler that keeps and "
                     "moves the particles that fit needs far fewer simulations: [sampler] method = "
                     "\"resample_move\" (docs/algorithm.md, \"Resample-move\")\n";
      }
      break;
    case Termination::kTooManyParticles:  // final: no limit to raise
      std::cerr << "stopped: " << summary.message << "\n";
      break;
    default:
      break;
  }
}

// The outcome of a run or a resume, printed; its exit code.
int Conclude(const services::RunOutcome& outcome, const ChecksPrinter& checks) {
  PrintOutcome(outcome, checks);
  const bool interrupted = outcome.history.summary.termination == Termination::kInterrupted;
  if (interrupted) {
    std::cerr << "interrupted; continue with: combabc resume " << outcome.history_path << "\n";
  }
  if (outcome.history.summary.termination == Termination::kTooManyFailures) {
    return kExitTooManyFailures;
  }
  return interrupted ? kExitInterrupted : 0;
}

// Under mpirun, rank 0's word if mpirun ends the job (a rank died): where the committed work is.
void NoteHistory(const Session& session, const std::string& path) {
  if (!session.primary() || !session.under_mpirun()) return;
  SetTermNote(
      "combabc: SIGTERM from mpirun (a rank died, or the job was stopped): the batches "
      "committed so far are kept in " +
      path + "; continue with: combabc resume " + path + "\n");
}

// A run or a resume (its request: RunRequest or ResumeRequest) under the progress display and
// Ctrl-C (Guarded), with what both print: the checks, the outcome and the answer; its exit code.
template <typename Args, typename Request>
int Calibrate(const Session& session,
              Args& args,
              const std::vector<bool>& temperatures,
              services::RunOutcome (*calibrate)(const Request&, SmcObserver*)) {
  Request& request = args.request;
  request.executor = session.executor();
  request.report = !args.no_report;
  request.on_report_progress = ReportProgressLine(session, args.quiet);
  ChecksPrinter checks;
  request.on_checks_before = checks.Callback();
  return Guarded(session, args.quiet, temperatures, [&](SmcObserver* observer) {
    const auto outcome = calibrate(request, observer);
    const int code = Conclude(outcome, checks);
    PrintAnswer(session, args.quiet, outcome.answer, outcome.strip);
    return code;
  });
}

int RunCommand(RunArgs& args, const Session& session) {
  args.request.on_history_path = [&session](const std::string& path) {
    NoteHistory(session, path);
  };
  if (IsModelChoiceConfig(args.request.config_path)) {
    services::RunRequest& request = args.request;
    request.executor = session.executor();
    request.report = !args.no_report;
    request.on_report_progress = ReportProgressLine(session, args.quiet);
    return RunModelChoiceCommand(request, args.quiet, session);
  }
  const std::vector<bool> temperatures = TemperatureSlotsOfConfig(args.request.config_path);
  return Calibrate(session, args, temperatures, &services::RunCalibration);
}

int ResumeCommand(ResumeArgs& args, const Session& session) {
  services::ResumeRequest& request = args.request;
  NoteHistory(session, request.history_path);
  services::StopLimits& limits = request.limits;
  if (args.max_simulations_option->count() > 0) limits.max_simulations = args.max_simulations;
  if (args.max_wall_time_option->count() > 0) limits.max_wall_time_s = args.max_wall_time;
  if (args.min_acceptance_rate_option->count() > 0) {
    limits.min_acceptance_rate = args.min_acceptance_rate;
  }
  if (args.max_failure_fraction_option->count() > 0) {
    limits.max_failure_fraction = args.max_failure_fraction;
  }
  if (args.waves_option->count() > 0) limits.num_waves = args.waves;
  const std::vector<bool> temperatures = TemperatureSlotsOfHistory(request.history_path);
  return Calibrate(session, args, temperatures, &services::ResumeCalibration);
}

}  // namespace

Command AddRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  services::RunRequest& request = args->request;
  auto* run = app.add_subcommand("run", "Run a calibration from a TOML config (docs/config.md)");
  run->add_option("CONFIG", request.config_path, "Config file")->required();
  run->add_option("-o,--output", request.output_directory, "Output directory (overrides [output])");
  // -1 (the default) means "not given"; a user may only ask for 0 (all cores) .. kMaxThreads.
  run->add_option("-j,--threads", request.threads, "Threads, 0 = all cores (overrides [sampler])")
      ->check(CLI::Range(0, kMaxThreads));
  run->add_flag("--overwrite", request.overwrite, "Replace an existing history file");
  run->add_option("--from",
                  request.start_from,
                  "Start from this finished run's posterior, adding the config's other "
                  "experiments to it (docs/algorithm.md)")
      ->check(CLI::ExistingFile);
  run->add_flag("--no-report", args->no_report, "Do not write figures at the end");
  run->add_flag("-q,--quiet", args->quiet, "No progress display, no answer at the end");
  AddNoCacheFlag(*run);
  return {run, [args](const Session& session) { return RunCommand(*args, session); }};
}

Command AddResumeCommand(CLI::App& app) {
  auto args = std::make_shared<ResumeArgs>();
  auto* resume = app.add_subcommand(
      "resume",
      "Continue a killed or interrupted run, or one stopped on a limit (raise it with the options "
      "below; they replace the config's [sampler] values and are recorded in the history)");
  resume->add_option("RUN.sqlite", args->request.history_path, "History file of the run")
      ->required();
  resume
      ->add_option(
          "-j,--threads", args->request.threads, "Threads, 0 = all cores (default: the run's)")
      ->check(CLI::Range(0, kMaxThreads));
  args->max_simulations_option =
      resume
          ->add_option(
              "--max-simulations", args->max_simulations, "Simulation budget, 0 = no limit")
          ->check(NonNegativeInteger());
  args->max_wall_time_option =
      resume
          ->add_option("--max-wall-time",
                       args->max_wall_time,
                       "Seconds this resume may run (each resume has its own), 0 = no limit")
          ->check(RealIn(0.0, std::numeric_limits<double>::max()));
  args->min_acceptance_rate_option =
      resume
          ->add_option(
              "--min-acceptance-rate", args->min_acceptance_rate, "Acceptance-rate floor, 0 = none")
          ->check(RealIn(0.0, 1.0));
  args->max_failure_fraction_option =
      resume
          ->add_option("--max-failure-fraction",
                       args->max_failure_fraction,
                       "Failed simulations tolerated, as a fraction; 1 = never stop")
          ->check(RealIn(0.0, 1.0));
  args->waves_option =
      resume
          ->add_option("--waves",
                       args->waves,
                       "Waves in all, for a run that did all its waves (max_waves): more continue "
                       "it as one longer run")
          ->check(CLI::Range(1, 1000000));
  resume->add_flag("--no-report", args->no_report, "Do not write figures at the end");
  resume->add_flag("-q,--quiet", args->quiet, "No progress display, no answer at the end");
  AddNoCacheFlag(*resume);
  return {resume, [args](const Session& session) { return ResumeCommand(*args, session); }};
}

}  // namespace combabc::cli
