#include "combabc/simulators/worker_simulator.hpp"

#include <chrono>
#include <optional>
#include <sstream>

#include "combabc/core/error.hpp"
#include "combabc/core/subprocess.hpp"
#include "simulator_io.hpp"

namespace combabc {
namespace si = simulators_internal;

namespace {
// A worker that answered its last request within kQuickAnswer is waited for by checking its
// stdout for up to kSpin before sleeping in poll(): on an idle virtual machine the sleep lets the
// CPU halt, and the wake-up then costs most of the round trip (docs/benchmarks.md: 98 us across
// cores without the spin, 20 us with it). A slower worker is waited for in poll() at once, so a
// simulator of a millisecond or more costs no CPU for the spin; one that became fast again
// (under kQuickAnswer even without the spin) is spun for again on its next request.
constexpr std::chrono::microseconds kSpin{50};
constexpr std::chrono::microseconds kQuickAnswer{200};
// A worker whose stdout or stdin closed is usually exiting: it is given this long to do so, so
// that the failure reason is its own exit status rather than the kill that follows.
constexpr double kExitGraceSeconds = 0.25;

std::string Requests(std::uint64_t n) {
  return std::to_string(n) + (n == 1 ? " request" : " requests");
}
}  // namespace

// One running worker: its process and its own working folder (removed with it).
class WorkerSimulator::Worker {
 public:
  Worker(std::string folder, const SubprocessOptions& spawn) : folder_(std::move(folder)) {
    try {
      process_.emplace(spawn);
    } catch (...) {
      WorkDirectory::Remove(folder_);
      throw;
    }
  }
  ~Worker() {
    if (process_ && process_->running()) {
      // End of input asks the worker to exit; one that does not within a moment is killed.
      process_->CloseInput();
      if (!process_->Wait(DeadlineAfter(0.5))) process_->Kill();
    }
    process_.reset();
    WorkDirectory::Remove(folder_);
  }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;
  Subprocess& process() { return *process_; }
  bool answers_quickly() const { return answers_quickly_; }
  void set_answers_quickly(bool quick) { answers_quickly_ = quick; }
  // The id of the next request (1, 2, ...), counting it as sent.
  std::uint64_t NextRequest() { return ++requests_; }
  // Why the worker stopped answering, for the failure reason, once its `stream` ("stdin",
  // "stdout") closed: its exit status when it exits within a moment, else that it closed the
  // stream (it is then killed); with the last line of its stderr either way.
  std::string Death(const char* stream) {
    const std::optional<ExitStatus> status = process_->Wait(DeadlineAfter(kExitGraceSeconds));
    std::string reason;
    if (status) {
      reason = "the worker " + Describe(*status);
    } else {
      process_->Kill();
      const std::uint64_t answered = requests_ > 0 ? requests_ - 1 : 0;
      reason = std::string("the worker closed its ") + stream + " after answering " +
               Requests(answered) + " (then killed)";
    }
    const std::string last = process_->LastStderrLine();
    return reason + (last.empty() ? "" : "; stderr: " + Printable(last, 160));
  }

 private:
  std::string folder_;
  std::optional<Subprocess> process_;
  bool answers_quickly_ = true;
  std::uint64_t requests_ = 0;
};

namespace {

std::string Seconds(double s) {
  std::ostringstream out;
  out << s << " s";
  return out.str();
}

// Checks "combabc-worker <version> <output size> [identity]"; returns the reason it is refused.
std::string CheckHandshake(const std::string& line, int output_size) {
  std::istringstream in(line);
  std::string protocol;
  std::string version;
  std::string size;
  in >> protocol >> version >> size;
  const std::string expected = std::string(kWorkerProtocol) + " " +
                               std::to_string(kWorkerProtocolVersion) + " " +
                               std::to_string(output_size);
  if (protocol != kWorkerProtocol) {
    return "its first line is " + Excerpt(line) + ", not a handshake \"" + expected + " ...\"";
  }
  if (version != std::to_string(kWorkerProtocolVersion)) {
    return "it speaks protocol version " + Excerpt(version) + "; this combabc speaks " +
           std::to_string(kWorkerProtocolVersion);
  }
  if (size != std::to_string(output_size)) {
    return "it declares " + Excerpt(size) + " outputs; the config declares " +
           std::to_string(output_size) + " ([simulator.outputs])";
  }
  return {};
}

}  // namespace

WorkerSimulator::WorkerSimulator(ExternalSimulatorOptions options)
    : options_(std::move(options)), work_([&] {
        std::string why;
        if (!options_.IsValid(SimulatorKind::kWorker, &why)) {
          throw Error(ErrorKind::kConfig, why, "", 0, "simulator");
        }
        return options_.work_directory;
      }()) {
  std::string reason;
  auto first = Start(&reason, &handshake_);
  if (!first) {
    throw Error(ErrorKind::kConfig,
                "the worker " + Excerpt(options_.argv.front()) + " did not start: " + reason,
                "",
                0,
                "simulator.argv");
  }
  idle_.push_back(std::move(first));
}

WorkerSimulator::~WorkerSimulator() {
  const std::lock_guard<std::mutex> lock(mutex_);
  idle_.clear();  // before work_ goes: each worker removes its folder
}

std::unique_ptr<WorkerSimulator::Worker> WorkerSimulator::Start(
    std::string* reason, std::string* first_handshake) const {
  std::unique_ptr<Worker> worker;
  try {
    const std::string folder = work_.MakeSubfolder("worker");
    SubprocessOptions spawn;
    // A worker serves one experiment: it is told which on its command line.
    spawn.argv = ExpandArgv(options_.argv,
                            "",
                            "",
                            folder,
                            options_.config_directory,
                            options_.experiment ? &*options_.experiment : nullptr);
    spawn.working_directory = folder;
    spawn.pipe_stdin = true;
    spawn.stderr_path = folder + "/stderr.txt";
    worker = std::make_unique<Worker>(folder, spawn);
  } catch (const std::runtime_error& e) {
    *reason = e.what();
    return nullptr;
  }
  std::string line;
  const ReadStatus read = worker->process().ReadLine(
      &line, kMaxSimulatorOutputBytes, DeadlineAfter(options_.startup_timeout_s));
  if (read == ReadStatus::kTimeout) {
    *reason = "no handshake within " + Seconds(options_.startup_timeout_s);
    return nullptr;
  }
  if (read != ReadStatus::kOk) {
    *reason = read == ReadStatus::kEof ? worker->Death("stdout") : "handshake line too long";
    return nullptr;
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  *reason = CheckHandshake(line, options_.output_size);
  if (!reason->empty()) return nullptr;
  if (!handshake_.empty() && line != handshake_) {
    *reason = "a new worker's handshake " + Excerpt(line) + " differs from the first one's " +
              Excerpt(handshake_);
    return nullptr;
  }
  if (handshake_.empty()) *first_handshake = line;
  return worker;
}

std::string WorkerSimulator::Attempt(Worker& worker,
                                     const ParameterView& theta,
                                     std::span<double> out,
                                     bool* in_step) const {
  *in_step = false;
  Subprocess& p = worker.process();
  const Deadline deadline = DeadlineAfter(options_.timeout_s);
  const std::uint64_t id = worker.NextRequest();
  if (!p.Write(si::RequestLine(id, theta), deadline)) {
    return p.timed_out() ? "timed out after " + Seconds(options_.timeout_s) + " (worker killed)"
                         : worker.Death("stdin");
  }
  std::string line;
  const auto sent = std::chrono::steady_clock::now();
  if (worker.answers_quickly()) p.SpinUntilReadable(kSpin);
  const ReadStatus read = p.ReadLine(&line, kMaxSimulatorOutputBytes, deadline);
  worker.set_answers_quickly(std::chrono::steady_clock::now() - sent < kQuickAnswer);
  if (read == ReadStatus::kTimeout) {
    return "timed out after " + Seconds(options_.timeout_s) + " (worker killed)";
  }
  if (read == ReadStatus::kTooLong) {
    return "response longer than " + std::to_string(kMaxSimulatorOutputBytes) + " bytes";
  }
  if (read == ReadStatus::kEof) return worker.Death("stdout");
  // One answer line per request, carrying the request's id: after an "ok"/"error" answer to this
  // request the worker is in step again, even when its values were refused (wrong count, NaN).
  // Anything more on its stdout already (an answer repeated) puts it out of step; one that comes
  // later is caught by the next request's id.
  std::string reason = si::ReadResponse(line, id, out, in_step);
  if (*in_step && p.OutputPending()) {
    *in_step = false;
    return "the worker wrote more than one line in answer to request " + std::to_string(id);
  }
  return reason;
}

void WorkerSimulator::Simulate(const ParameterView& theta,
                               RandomStream& /*rng*/,
                               std::span<double> out) const {
  std::string reason;
  const int attempts = options_.retries + 1;
  for (int attempt = 1; attempt <= attempts; ++attempt) {
    std::unique_ptr<Worker> worker;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!idle_.empty()) {
        worker = std::move(idle_.back());
        idle_.pop_back();
      }
    }
    if (!worker) {
      worker = Start(&reason, nullptr);
      if (!worker) {
        reason.insert(0, "a new worker did not start: ");
        continue;
      }
    }
    bool in_step = false;
    reason = Attempt(*worker, theta, out, &in_step);
    // A worker still in step with the protocol is kept; any other failure leaves it in an
    // unknown state: it is killed (with its group) and replaced by the next call.
    if (in_step) {
      const std::lock_guard<std::mutex> lock(mutex_);
      idle_.push_back(std::move(worker));
    } else {
      worker->process().Kill();
    }
    if (reason.empty()) return;
  }
  if (attempts > 1) reason += " (" + std::to_string(attempts) + " attempts)";
  throw SimulationFailed(reason);
}

}  // namespace combabc
