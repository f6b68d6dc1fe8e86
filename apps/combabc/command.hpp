#pragma once
// What every subcommand of the CLI has: its entry in the command line and its job, the way a job
// ends (a failure is one line and an exit code) and the option checks the subcommands share.
#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "combabc/export/answer.hpp"
#include "combabc/export/strip.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/services/report.hpp"
#include "session.hpp"

namespace combabc::cli {

// sysexits.h codes for failures that are not combabc::Error.
constexpr int kExitUsage = 64;
constexpr int kExitSoftware = 70;
// A run, resume or enumeration stopped by SIGINT or SIGTERM during a wave (128 + SIGINT).
constexpr int kExitInterrupted = 130;
// The same bound as [sampler] threads (SmcOptions::IsValid).
constexpr int kMaxThreads = 4096;

// One subcommand: its entry in the command line, whose options fill values that `run` reads, and
// `run`, which does the job once the command line named it and returns the exit code.
struct Command {
  CLI::App* app = nullptr;
  std::function<int(const Session&)> run;
};

// Runs `job` with what every command has: the progress display on stderr (on a terminal, on rank
// 0, not with `quiet`) and SIGINT/SIGTERM handling (interrupt.hpp), given to `job` as one
// observer. A combabc::Error ends it as one line "combabc: <kind>: <message>" and its sysexits
// code; any other exception as "internal error" and 70. `job` returns the exit code.
int Guarded(const Session& session, bool quiet, const std::function<int(SmcObserver*)>& job);
// The same, with `temperatures` labelling the waves' threshold slots in the progress lines
// (ProgressDisplay; TemperatureSlotsOfConfig, TemperatureSlotsOfHistory).
int Guarded(const Session& session,
            bool quiet,
            const std::vector<bool>& temperatures,
            const std::function<int(SmcObserver*)>& job);

// Per threshold slot of a run, whether it holds a noise-aware component's temperature: from its
// config file, or (resume) from its history. Empty when either cannot be read: the job itself
// then says why.
std::vector<bool> TemperatureSlotsOfConfig(const std::string& config_path);
std::vector<bool> TemperatureSlotsOfHistory(const std::string& history_path);

// Guarded, for a command that writes or prints only: rank 0 does it, the others wait for its code.
int PrimaryOnly(const Session& session, const std::function<int()>& job);

// The answer in numbers of the job's outcome (read back with its checks), on stdout: at the end of
// run, resume and enumerate, on rank 0, unless `quiet`. A history that could not be read back is
// said on stderr; the command's exit code stays the job's. The sensor's strip (`strip`) comes
// first: the picture, with colour where stdout is a terminal that has it, and the verdict line.
void PrintAnswer(const Session& session,
                 bool quiet,
                 const std::optional<Answer>& answer,
                 const std::optional<StripLayout>& strip = std::nullopt);

// "writing report ..." on stderr while the report is drawn (it takes seconds to a minute): on a
// terminal one line updated with the figures drawn, otherwise (`off_terminal`) that line once.
// Nothing with `quiet` or off rank 0. `combabc report` says it on a terminal only: off one, its
// stderr stays what it was, empty or the one line of its error.
services::ReportProgress ReportProgressLine(const Session& session,
                                            bool quiet,
                                            bool off_terminal = true);

// --no-cache, for the commands that build the sensor: its precomputed pieces are built afresh and
// not stored (docs/model.md, "Start-up and the precompute cache"). It empties COMBABC_CACHE_DIR
// for this process, which is where plate::DefaultPrecomputeCache looks first.
void AddNoCacheFlag(CLI::App& command);

// A whole number in [0, INT64_MAX], read strictly: CLI11's own conversion turns an out-of-range
// value into INT64_MAX without a word, and its range check prints DBL_MAX's 309 digits.
CLI::Validator NonNegativeInteger();

// A number in [low, high] (high may be infinity), never NaN: CLI11's NonNegativeNumber and Range
// let nan through, and NonNegativeNumber prints DBL_MAX's 309 digits for a negative value.
CLI::Validator RealIn(double low, double high);

}  // namespace combabc::cli
