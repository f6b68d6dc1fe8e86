// combabc: the command-line front end. Thin by design: parsing, progress display and exit codes
// here; every job is a call into combabc::services.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/services/enumerate.hpp"
#include "combabc/services/history_tools.hpp"
#include "combabc/services/report.hpp"
#include "combabc/services/run.hpp"
#include "combabc/services/simulate.hpp"
#include "combabc/services/design.hpp"
#include "interrupt.hpp"
#include "progress_display.hpp"
#ifdef COMBABC_HAVE_MPI
#include "combabc/mpi/mpi_executor.hpp"
#endif

namespace {

// sysexits.h codes for failures that are not combabc::Error.
constexpr int kExitUsage = 64;
constexpr int kExitSoftware = 70;
// A run stopped because too many simulations failed: the simulator, not the calibration, is the
// problem (sysexits EX_UNAVAILABLE). Its finished waves are kept.
constexpr int kExitTooManyFailures = 69;
// The same bound as [sampler] threads (SmcOptions::IsValid).
constexpr int kMaxThreads = 4096;

// A whole number in [0, INT64_MAX], read strictly: CLI11's own conversion turns an out-of-range
// value into INT64_MAX without a word, and its range check prints DBL_MAX's 309 digits.
CLI::Validator NonNegativeInteger() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::int64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [at, error] = std::from_chars(text.data(), end, value);
        if (text.empty() || error != std::errc() || at != end || value < 0) {
          return "must be a whole number from 0 to " +
                 std::to_string(std::numeric_limits<std::int64_t>::max()) + ", not '" + text + "'";
        }
        return {};
      },
      "INT >= 0");
}

// A number in [low, high] (high may be infinity), never NaN: CLI11's NonNegativeNumber and Range
// let nan through, and NonNegativeNumber prints DBL_MAX's 309 digits for a negative value.
CLI::Validator RealIn(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool parsed = !text.empty() && end == text.c_str() + text.size();
        if (!parsed || std::isnan(value) || value < low || value > high) {
          std::ostringstream message;
          message << "must be a number ";
          if (std::isinf(high)) {
            message << ">= " << low;
          } else if (high == std::numeric_limits<double>::max()) {
            message << ">= " << low << ", finite";
          } else {
            message << "in [" << low << ", " << high << "]";
          }
          message << ", not '" << text << "'";
          return message.str();
        }
        return {};
      },
      "NUMBER");
}

void PrintOutcome(const combabc::services::RunOutcome& outcome) {
  const combabc::RunSummary& summary = outcome.history.summary;
  std::cout << summary.BriefReport() << "\n"
            << "history: " << outcome.history_path << "\n";
  if (!outcome.report_directory.empty()) {
    std::cout << "report:  " << outcome.report_directory << "/index.html\n";
  }
  // A run that gave up says why on stderr too, where a user watching the progress looks.
  using combabc::Termination;
  switch (summary.termination) {
    case Termination::kBudgetExhausted:
    case Termination::kAcceptanceRateTooLow:
    case Termination::kWallTimeExceeded:
    case Termination::kTooManyFailures:
      std::cerr << "stopped: " << summary.message << "\n"
                << "finished waves are kept; to go on, raise the limit: combabc resume "
                << outcome.history_path << " "
                << combabc::services::LimitOption(summary.termination) << " ...\n";
      break;
    default:
      break;
  }
}

// A build for a newer instruction set (COMBABC_ARCH) dies of SIGILL on an older CPU; say why
// instead. Checked first thing, before any vectorised code of ours runs.
bool CpuRunsThisBuild() {
  const char* missing = nullptr;
#if defined(__AVX512F__)
  if (!__builtin_cpu_supports("avx512f")) missing = "AVX-512";
#endif
#if defined(__AVX2__)
  if (!__builtin_cpu_supports("avx2")) missing = "AVX2";
#endif
#if defined(__FMA__)
  if (!__builtin_cpu_supports("fma")) missing = "FMA";
#endif
  if (missing == nullptr) return true;
  std::cerr << "combabc: this build (" COMBABC_VERSION ") needs a CPU with " << missing
            << "; rebuild with another COMBABC_ARCH (empty: portable)\n";
  return false;
}

// What was printed reached standard output, or (a full disk, /dev/full, a closed pipe's reader
// gone) exit 74 saying so: `combabc verify RUN > report.txt` on a full disk must not exit 0.
// `code` is the command's own exit code; an earlier failure keeps its code and its message.
int CheckStandardOutput(int code) {
  std::cout.flush();
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int error = errno;
  if (flushed && std::ferror(stdout) == 0 && !std::cout.fail()) return code;
  if (code != 0) return code;
  std::cerr << "combabc: I/O error: cannot write to standard output"
            << (error != 0 ? std::string(": ") + std::strerror(error) : std::string()) << "\n";
  return combabc::ExitCode(combabc::ErrorKind::kIo);
}

// The ranking (best ten), the greedy selection and where the files are.
void PrintDesign(const combabc::services::DesignOutcome& o) {
  const auto& r = o.result;
  std::printf("design from %s; %zu candidates, noise sigma on the normalised profile\n",
              o.population.c_str(),
              o.candidates.size());
  std::printf("prior: %.2f bits of marginal entropy, %.0f clamps identified\n",
              r.prior_entropy,
              r.prior_identified);
  std::vector<std::size_t> order(o.candidates.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return r.scores[a].information_gain > r.scores[b].information_gain;
  });
  std::printf(
      "rank  load x cm  load y  scan cm     line   gain bits (se)   identified  wrong    ess\n");
  for (std::size_t rank = 0; rank < std::min<std::size_t>(10, order.size()); ++rank) {
    const auto& c = o.candidates[order[rank]];
    const auto& s = r.scores[order[rank]];
    std::printf("%4zu  %9.1f  %6.2f  %5.1f-%-5.1f %5.2f  %6.2f (%.2f)    %10.1f  %5.1f  %5.0f\n",
                rank + 1,
                c.load_x * 100,
                c.load_y_fraction,
                c.scan_from * 100,
                c.scan_to * 100,
                c.scan_y_fraction,
                s.information_gain,
                s.information_gain_se,
                s.identified,
                s.wrong,
                s.effective_particles);
  }
  std::printf("greedy selection:\n");
  for (std::size_t step = 0; step < r.selected.size(); ++step) {
    const auto& c = o.candidates[static_cast<std::size_t>(r.selected[step])];
    const auto& s = r.cumulative[step];
    std::printf(
        "  %zu. load %.1f cm (y %.2f), scan %.1f-%.1f cm (y %.2f): %.2f bits in all, "
        "%.1f clamps identified, %.1f wrong\n",
        step + 1,
        c.load_x * 100,
        c.load_y_fraction,
        c.scan_from * 100,
        c.scan_to * 100,
        c.scan_y_fraction,
        s.information_gain,
        s.identified,
        s.wrong);
  }
  double least = std::numeric_limits<double>::infinity();
  for (const auto& s : r.cumulative) least = std::min(least, s.effective_particles);
  if (!o.exhaustive && least < 20) {
    std::printf(
        "note: the reweighted population falls to %.0f effective particles: the gains and "
        "identified counts are upper bounds (a larger population: more accepted "
        "particles, or [design] particles)\n",
        least);
  }
  std::printf("design: %s (%.2f s; next experiment: %s/next_experiment.toml)\n",
              o.directory.c_str(),
              o.wall_seconds,
              o.directory.c_str());
}

}  // namespace

int main(int argc, char** argv) try {
  if (!CpuRunsThisBuild()) return 70;
  CLI::App app{"combabc " COMBABC_VERSION
               " - combinatorial ABC-SMC calibration of binary (on/off) simulator parameters"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "combabc " COMBABC_VERSION);

  combabc::services::RunRequest request;
  bool quiet = false, no_report = false;
  auto* run = app.add_subcommand("run", "Run a calibration from a TOML config (docs/config.md)");
  run->add_option("CONFIG", request.config_path, "Config file")->required();
  run->add_option("-o,--output", request.output_directory, "Output directory (overrides [output])");
  // -1 (the default) means "not given"; a user may only ask for 0 (all cores) .. kMaxThreads.
  run->add_option("-j,--threads", request.threads, "Threads, 0 = all cores (overrides [sampler])")
      ->check(CLI::Range(0, kMaxThreads));
  run->add_flag("--overwrite", request.overwrite, "Replace an existing history file");
  run->add_flag("--no-report", no_report, "Do not write figures at the end");
  run->add_flag("-q,--quiet", quiet, "No progress display");

  std::string history;
  combabc::services::ResumeRequest resume_request;
  std::int64_t max_simulations = 0;
  double max_wall_time = 0.0, min_acceptance_rate = 0.0, max_failure_fraction = 0.0;
  auto* resume = app.add_subcommand(
      "resume",
      "Continue a killed or interrupted run, or one stopped on a limit (raise it with the options "
      "below; they replace the config's [sampler] values and are recorded in the history)");
  resume->add_option("RUN.sqlite", history, "History file of the run")->required();
  resume
      ->add_option(
          "-j,--threads", resume_request.threads, "Threads, 0 = all cores (default: the run's)")
      ->check(CLI::Range(0, kMaxThreads));
  auto* max_simulations_option =
      resume->add_option("--max-simulations", max_simulations, "Simulation budget, 0 = no limit")
          ->check(NonNegativeInteger());
  auto* max_wall_time_option =
      resume
          ->add_option("--max-wall-time",
                       max_wall_time,
                       "Seconds this resume may run (each resume has its own), 0 = no limit")
          ->check(RealIn(0.0, std::numeric_limits<double>::max()));
  auto* min_acceptance_rate_option =
      resume
          ->add_option(
              "--min-acceptance-rate", min_acceptance_rate, "Acceptance-rate floor, 0 = none")
          ->check(RealIn(0.0, 1.0));
  auto* max_failure_fraction_option =
      resume
          ->add_option("--max-failure-fraction",
                       max_failure_fraction,
                       "Failed simulations tolerated, as a fraction; 1 = never stop")
          ->check(RealIn(0.0, 1.0));
  resume->add_flag("--no-report", no_report, "Do not write figures at the end");
  resume->add_flag("-q,--quiet", quiet, "No progress display");

  combabc::services::EnumerateRequest enumerate_request;
  auto* enumerate = app.add_subcommand(
      "enumerate", "Exact ABC posterior by simulating every configuration of the free bits");
  enumerate->add_option("CONFIG", enumerate_request.config_path, "Config file")->required();
  enumerate
      ->add_option("--threshold",
                   enumerate_request.thresholds,
                   "One per threshold component (default: the config's final thresholds)")
      ->check(RealIn(0.0, std::numeric_limits<double>::infinity()));
  enumerate->add_option("-o,--output", enumerate_request.output_directory, "Output directory");
  enumerate
      ->add_option(
          "-j,--threads", enumerate_request.threads, "Threads, 0 = all cores (overrides [sampler])")
      ->check(CLI::Range(0, kMaxThreads));
  enumerate->add_flag(
      "--overwrite", enumerate_request.overwrite, "Replace an existing history and its files");
  enumerate->add_option("--top", enumerate_request.top, "Configurations in top_configurations.csv")
      ->check(CLI::Range(1, 1000000));
  enumerate->add_flag("--no-report", no_report, "Do not write figures at the end");
  enumerate->add_flag("-q,--quiet", quiet, "No progress display");

  std::string sim_config, clamps, sim_out = "profile.csv";
  bool overwrite_profile = false;
  auto* simulate = app.add_subcommand("simulate", "Simulate one bit (clamp) configuration to CSV");
  simulate->add_option("CONFIG", sim_config, "Config file (its simulator is used)")->required();
  simulate
      ->add_option(
          "--clamps", clamps, "One 0/1 per bit (the sensor: per clamp, 1 = fixed), e.g. 0110...")
      ->required();
  simulate->add_option("-o,--output", sim_out, "CSV to write (default profile.csv)");
  simulate->add_flag("--overwrite", overwrite_profile, "Replace an existing CSV at that path");

  combabc::services::DesignRequest design_request;
  bool no_figure = false;
  auto* design = app.add_subcommand(
      "design", "Rank candidate experiments ([design]) by the information they would add");
  design->add_option("CONFIG", design_request.config_path, "Config file with a [design] table")
      ->required();
  design->add_option("--posterior",
                     design_request.posterior_path,
                     "A finished run's history: start from its posterior (default: the prior)");
  design->add_option(
      "-o,--output", design_request.output_directory, "Directory (default: design/ in [output])");
  design->add_option("-j,--threads", design_request.threads, "Threads, 0 = all cores")
      ->check(CLI::Range(0, kMaxThreads));
  design->add_flag("--overwrite", design_request.overwrite, "Write into an existing directory");
  design->add_flag("--no-figure", no_figure, "Skip identifiability.<fmt> (needs matplotlib)");

  std::string out_dir;
  bool overwrite_dir = false;
  constexpr const char* kOverwriteDir =
      "Write into DIR even if combabc did not create it (replaces only same-named files)";
  auto* report = app.add_subcommand(
      "report", "Write figures ([output] figures: png, svg, pdf) and index.html of a run");
  report->add_option("RUN.sqlite", history, "History file of the run")->required();
  report->add_option("-o,--output", out_dir, "Directory (default: report/ beside the history)");
  report->add_flag("--overwrite", overwrite_dir, kOverwriteDir);

  auto* exporter = app.add_subcommand("export", "Export a run to CSV and JSON (pandas, MATLAB)");
  exporter->add_option("RUN.sqlite", history, "History file of the run")->required();
  exporter->add_option("-o,--output", out_dir, "Directory (default: export/ beside the history)");
  exporter->add_flag("--overwrite", overwrite_dir, kOverwriteDir);
  bool no_netcdf = false;
  exporter->add_flag(
      "--no-netcdf", no_netcdf, "Skip inference_data.nc (ArviZ layout; needs python3-xarray)");

  auto* verify = app.add_subcommand(
      "verify", "Check a history's integrity (structure, checksums); exit 0 if sound, 65 if not");
  verify->add_option("RUN.sqlite", history, "History file of the run")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return CheckStandardOutput(app.exit(e));
  } catch (const CLI::CallForAllHelp& e) {
    return CheckStandardOutput(app.exit(e));
  } catch (const CLI::CallForVersion& e) {
    return CheckStandardOutput(app.exit(e));
  } catch (const CLI::ParseError& e) {
    // One line, like every other error; the full usage is one --help away.
    std::cerr << "combabc: usage error: " << combabc::Printable(e.what(), 400)
              << " (see combabc --help)\n";
    return kExitUsage;
  }

  // Under mpirun (and only there: a plain run never touches MPI) every rank runs the same command
  // (SPMD, docs/architecture.md): run, resume and enumerate spread their simulations over the
  // ranks; rank 0 alone prints and writes files, the others are silent; all exit with rank 0's
  // code.
  bool primary = true;
  combabc::services::ExecutorFactory executor;
#ifdef COMBABC_HAVE_MPI
  std::optional<combabc::mpi::MpiSession> mpi;
  if (combabc::mpi::MpiSession::LaunchedByMpirun()) {
    mpi.emplace(&argc, &argv);
    primary = mpi->rank() == 0;
    executor = [](int threads) { return std::make_unique<combabc::mpi::MpiExecutor>(threads); };
  }
#endif
  if (!primary) {
    std::cout.setstate(std::ios::failbit);
    std::cerr.setstate(std::ios::failbit);
  }
  request.executor = executor;
  enumerate_request.executor = executor;
  // Under mpirun, rank 0's word if mpirun ends the job (a rank died): where the committed work is.
  const bool under_mpirun = static_cast<bool>(executor);
  auto note_history = [&](const std::string& path) {
    if (!primary || !under_mpirun) return;
    combabc::cli::SetTermNote(
        "combabc: SIGTERM from mpirun (a rank died, or the job was stopped): the batches "
        "committed so far are kept in " +
        path + "; continue with: combabc resume " + path + "\n");
  };
  request.on_history_path = note_history;
  if (*resume) note_history(history);
  if (*enumerate && primary && under_mpirun) {
    combabc::cli::SetTermNote(
        "combabc: SIGTERM from mpirun (a rank died, or the job was stopped): the enumeration "
        "ends; nothing is written (an enumeration cannot be resumed)\n");
  }
  resume_request.history_path = history;
  resume_request.report = !no_report;
  resume_request.executor = executor;
  combabc::services::StopLimits& limits = resume_request.limits;
  if (max_simulations_option->count() > 0) limits.max_simulations = max_simulations;
  if (max_wall_time_option->count() > 0) limits.max_wall_time_s = max_wall_time;
  if (min_acceptance_rate_option->count() > 0) limits.min_acceptance_rate = min_acceptance_rate;
  if (max_failure_fraction_option->count() > 0) limits.max_failure_fraction = max_failure_fraction;
  // The command itself; returns the exit code.
  auto run_command = [&]() -> int {
    combabc::cli::ProgressDisplay progress(primary && isatty(STDERR_FILENO) != 0);
    combabc::cli::InterruptObserver interrupt(quiet || !primary ? nullptr : &progress);
    combabc::SmcObserver* observer = &interrupt;
    bool interrupted = false;
    try {
      if (*run || *resume) {
        request.report = !no_report;
        const auto outcome = *run ? combabc::services::RunCalibration(request, observer)
                                  : combabc::services::ResumeCalibration(resume_request, observer);
        PrintOutcome(outcome);
        interrupted = outcome.history.summary.termination == combabc::Termination::kInterrupted;
        if (interrupted) {
          std::cerr << "interrupted; continue with: combabc resume " << outcome.history_path
                    << "\n";
        }
        if (outcome.history.summary.termination == combabc::Termination::kTooManyFailures) {
          return kExitTooManyFailures;
        }
      } else if (*enumerate) {
        enumerate_request.report = !no_report;
        const auto outcome = combabc::services::RunEnumeration(enumerate_request, observer);
        interrupted = outcome.interrupted;
        if (interrupted) {
          std::cerr << "interrupted after " << outcome.enumerated << " of "
                    << outcome.configurations
                    << " configurations; nothing written (an enumeration cannot be resumed)\n";
        } else {
          std::cout << "enumerated " << outcome.configurations
                    << " configurations: " << outcome.accepted << " accepted, evidence "
                    << outcome.evidence << " (" << outcome.wall_seconds << " s)\n"
                    << "history: " << outcome.history_path << "\n"
                    << "tables:  " << outcome.enumeration_directory << "\n";
          if (!outcome.report_directory.empty()) {
            std::cout << "report:  " << outcome.report_directory << "/index.html\n";
          }
        }
      } else if (!primary) {
        // The other commands write or print only: rank 0 does them, the others wait for its code.
      } else if (*simulate) {
        combabc::services::SimulateConfiguration(sim_config, clamps, sim_out, overwrite_profile);
        std::cout << "wrote " << sim_out << "\n";
      } else if (*design) {
        design_request.figure = !no_figure;
        PrintDesign(combabc::services::RunDesign(design_request));
      } else if (*report) {
        // Written first, printed after: a failure prints no half line on stdout.
        const auto directory = combabc::services::WriteReport(history, out_dir, overwrite_dir);
        std::cout << "report: " << directory << "/index.html\n";
      } else if (*verify) {
        const auto outcome = combabc::services::VerifyHistory(history);
        for (const std::string& line : outcome.lines) {
          (outcome.ok ? std::cout : std::cerr)
              << (outcome.ok ? "" : "combabc: data error: ") << line << "\n";
        }
        if (!outcome.ok) return combabc::ExitCode(combabc::ErrorKind::kData);
      } else if (*exporter) {
        const auto outcome =
            combabc::services::ExportHistory(history, out_dir, overwrite_dir, !no_netcdf);
        std::cout << "export: " << outcome.directory << "\n";
        if (!outcome.note.empty()) std::cerr << "combabc: note: " << outcome.note << "\n";
      }
    } catch (const combabc::Error& e) {
      progress.Clear();
      std::cerr << "combabc: " << ToString(e.kind()) << ": " << e.what() << "\n";
      return combabc::ExitCode(e.kind());
    } catch (const std::exception& e) {
      progress.Clear();
      std::cerr << "combabc: internal error: " << combabc::Printable(e.what(), 400) << "\n";
      return kExitSoftware;
    }
    return interrupted ? 130 : 0;
  };
  // The other ranks print nothing (their std::cout is failed on purpose).
  const int code = primary ? CheckStandardOutput(run_command()) : run_command();
#ifdef COMBABC_HAVE_MPI
  if (mpi) return combabc::mpi::ExitCodeOfPrimary(code);
#endif
  return code;
} catch (const std::exception& e) {
  // Setting up the command line (CLI11, the progress display) can throw too: exit 70, no abort.
  std::cerr << "combabc: internal error: " << combabc::Printable(e.what(), 400) << "\n";
  return kExitSoftware;
} catch (...) {
  std::cerr << "combabc: internal error: unknown exception\n";
  return kExitSoftware;
}
