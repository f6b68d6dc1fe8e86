#include "combabc/simulators/command_simulator.hpp"

#include <fstream>
#include <sstream>

#include "combabc/core/bounded_read.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/subprocess.hpp"
#include "simulator_io.hpp"

namespace combabc {
namespace si = simulators_internal;
namespace {

// The last line the program wrote to stderr, for the failure reason (one line, printable).
std::string StderrTail(Subprocess& child) {
  const std::string last = child.LastStderrLine();
  return last.empty() ? "" : "; stderr: " + Printable(last, 160);
}

bool WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return static_cast<bool>(out.flush());
}

std::string TimeoutText(double seconds) {
  std::ostringstream s;
  s << "timed out after " << seconds << " s (process group killed)";
  return s.str();
}

// Removes the call's folder on every path out of an attempt.
struct CallFolder {
  explicit CallFolder(std::string p) : path(std::move(p)) {}
  std::string path;
  CallFolder(const CallFolder&) = delete;
  CallFolder& operator=(const CallFolder&) = delete;
  ~CallFolder() { WorkDirectory::Remove(path); }
};

}  // namespace

CommandSimulator::CommandSimulator(ExternalSimulatorOptions options)
    : options_(std::move(options)), work_([&] {
        std::string why;
        if (!options_.IsValid(SimulatorKind::kCommand, &why)) {
          throw Error(ErrorKind::kConfig, why, "", 0, "simulator");
        }
        return options_.work_directory;
      }()) {
  // A program that is not there would fail every simulation of the run, one by one: said once,
  // before anything runs, as the program would be looked up in a call's folder. (One named by a
  // per-call placeholder cannot be checked before the call.)
  const std::string& named = options_.argv.front();
  if (named.find("{workdir}") == std::string::npos && named.find("{params}") == std::string::npos &&
      named.find("{output}") == std::string::npos) {
    const std::string program = ExpandArgv({named}, "", "", "", options_.config_directory).front();
    const std::string why = ProgramProblem(program, options_.work_directory + "/call");
    if (!why.empty()) {
      throw Error(ErrorKind::kConfig, "the command cannot be run: " + why, "", 0, "simulator.argv");
    }
  }
}

void CommandSimulator::Simulate(const ParameterView& theta,
                                RandomStream& /*rng*/,
                                std::span<double> out) const {
  std::string reason;
  const int attempts = options_.retries + 1;
  for (int attempt = 1; attempt <= attempts; ++attempt) {
    reason = Attempt(theta, out);
    if (reason.empty()) return;
  }
  if (attempts > 1) reason += " (" + std::to_string(attempts) + " attempts)";
  throw SimulationFailed(reason);
}

std::string CommandSimulator::Attempt(const ParameterView& theta, std::span<double> out) const {
  const CallFolder folder(work_.MakeSubfolder("call"));
  const bool json_in = options_.params_format == DataFormat::kJson;
  const std::string params_path = folder.path + (json_in ? "/params.json" : "/params.csv");
  const bool json_out = options_.results_format == DataFormat::kJson;
  const std::string output_path = folder.path + (json_out ? "/output.json" : "/output.csv");
  const std::string stderr_path = folder.path + "/stderr.txt";
  const std::string params =
      json_in ? si::ParamsJson(theta, options_.real_names, Experiment())
              : si::ParamsCsv(theta, options_.bit_names, options_.real_names, Experiment());
  if (options_.params == Transport::kFile && !WriteFile(params_path, params)) {
    return "cannot write " + params_path;
  }
  SubprocessOptions spawn;
  spawn.argv = ExpandArgv(options_.argv,
                          params_path,
                          output_path,
                          folder.path,
                          options_.config_directory,
                          Experiment());
  spawn.working_directory = folder.path;
  spawn.pipe_stdin = options_.params == Transport::kStdin;
  spawn.stderr_path = stderr_path;
  const Deadline deadline = DeadlineAfter(options_.timeout_s);
  std::optional<Subprocess> child;
  try {
    child.emplace(spawn);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  if (spawn.pipe_stdin) {
    // A program that exits without reading its stdin is not a failure by itself.
    child->Write(params, deadline);
    child->CloseInput();
    if (child->timed_out()) {
      child->Kill();
      return TimeoutText(options_.timeout_s);
    }
  }
  std::string stdout_text;
  const ReadStatus read = child->ReadToEnd(&stdout_text, kMaxSimulatorOutputBytes, deadline);
  if (read == ReadStatus::kTimeout) {
    child->Kill();
    return TimeoutText(options_.timeout_s);
  }
  if (read == ReadStatus::kTooLong) {
    child->Kill();
    return "wrote more than " + FormatBytes(kMaxSimulatorOutputBytes) + " to stdout";
  }
  const std::optional<ExitStatus> status = child->Wait(deadline);
  if (!status) {
    child->Kill();
    return TimeoutText(options_.timeout_s);
  }
  if (!status->ok()) return Describe(*status) + StderrTail(*child);
  std::string text;
  std::string source = "stdout";
  if (options_.results == Transport::kFile) {
    source = "output file";
    try {
      text =
          ReadBoundedFile(output_path, kMaxSimulatorOutputBytes, "output file", ErrorKind::kData);
    } catch (const Error&) {
      return "exited with status 0 but wrote no readable output file" + StderrTail(*child);
    }
  } else {
    text = std::move(stdout_text);
  }
  std::string reason = si::ReadValues(text, options_.results_format, out);
  if (!reason.empty()) return source + ": " + reason;
  return {};
}

}  // namespace combabc
