// combabc: the command-line front end. Thin by design: parsing, progress display and exit codes
// here, one function per subcommand (subcommands.hpp); every job is a call into
// combabc::services.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <optional>
#include <vector>

#include "combabc/core/error.hpp"
#include "command.hpp"
#include "session.hpp"
#include "subcommands.hpp"

namespace {

using combabc::cli::CheckStandardOutput;
using combabc::cli::kExitSoftware;

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

// Reads the command line into the subcommands' values; the exit code when that was all there was
// to do (--help, --version, a usage error).
std::optional<int> Parse(CLI::App& app, int argc, char** argv) {
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
    return combabc::cli::kExitUsage;
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) try {
  namespace cli = combabc::cli;
  if (!CpuRunsThisBuild()) return kExitSoftware;
  CLI::App app{"combabc " COMBABC_VERSION
               " - combinatorial ABC-SMC calibration of binary (on/off) simulator parameters"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "combabc " COMBABC_VERSION);
  // In the order of `combabc --help`.
  const std::vector<cli::Command> commands = {cli::AddRunCommand(app),
                                              cli::AddResumeCommand(app),
                                              cli::AddEnumerateCommand(app),
                                              cli::AddSimulateCommand(app),
                                              cli::AddDesignCommand(app),
                                              cli::AddReportCommand(app),
                                              cli::AddExportCommand(app),
                                              cli::AddVerifyCommand(app)};
  if (const std::optional<int> code = Parse(app, argc, argv)) return *code;
  cli::Session session(&argc, &argv);
  for (const cli::Command& command : commands) {
    if (*command.app) return session.Finish(command.run(session));
  }
  return kExitSoftware;  // not reached: CLI11 requires one subcommand
} catch (const std::exception& e) {
  // Setting up the command line (CLI11, the progress display) can throw too: exit 70, no abort.
  std::cerr << "combabc: internal error: " << combabc::Printable(e.what(), 400) << "\n";
  return kExitSoftware;
} catch (...) {
  std::cerr << "combabc: internal error: unknown exception\n";
  return kExitSoftware;
}
