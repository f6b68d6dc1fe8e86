#pragma once
// The subcommands of combabc, one function each that adds it to the command line (its options,
// in the order of its --help) and returns it with its job. The man page (docs/man/combabc.1) and
// the bash completion (scripts/completion/combabc.bash) list the same commands and options
// (tests/packaging/cli_docs_test.sh).
#include <CLI/CLI.hpp>

#include "command.hpp"

namespace combabc::cli {

// run_commands.cpp: a calibration, and its continuation.
Command AddRunCommand(CLI::App& app);
Command AddResumeCommand(CLI::App& app);
// enumerate_command.cpp: the exact posterior by enumeration.
Command AddEnumerateCommand(CLI::App& app);
// simulate_command.cpp: one configuration's profile.
Command AddSimulateCommand(CLI::App& app);
// design_command.cpp: candidate experiments ranked.
Command AddDesignCommand(CLI::App& app);
// history_commands.cpp: what reads a run's history.
Command AddReportCommand(CLI::App& app);
Command AddExportCommand(CLI::App& app);
Command AddVerifyCommand(CLI::App& app);

}  // namespace combabc::cli
