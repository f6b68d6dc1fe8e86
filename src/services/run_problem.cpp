// services::RunProblem: a problem the caller built (the Python module's combabc.run(problem) and
// combabc.resume(path, problem)), through the steps a config's run and resume take (run_steps).
#include <memory>
#include <optional>

#include "combabc/core/error.hpp"
#include "combabc/core/executor.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/services/run.hpp"
#include "services/steps/problem.hpp"
#include "services/steps/read_back.hpp"
#include "services/steps/report_checks.hpp"
#include "services/steps/run_fingerprint.hpp"
#include "services/steps/run_steps.hpp"
#include "services/steps/start_from.hpp"

namespace combabc::services {
namespace {

bool HasPart(const RunMetadata& m, const char* name) {
  for (const auto& [part, digest] : m.fingerprint) {
    if (part == name) return true;
  }
  return false;
}

// The stored run's checks, then its resume point under the limits this resume sets: as
// ResumeCalibration, with the caller's problem in place of a config's.
ResumePoint BeginProblemResume(const ProblemRunRequest& request,
                               const RunMetadata& described,
                               SmcOptions& options,
                               Executor& executor,
                               std::optional<HistoryStore>& store) {
  const std::string& path = request.history_path;
  const RunMetadata stored = HistoryStore::Open(path, true).LoadMetadata();
  if (!HasPart(stored, kCallerProblemPart)) {
    throw Error(ErrorKind::kUsage,
                "a config run's history; resume it with combabc.resume(path), without a problem",
                path);
  }
  const bool finished = CheckResumable(stored, request.limits, request.names, path);
  if (request.report) CheckReportPossible(ReportDirectory(path));
  store.emplace(HistoryStore::Open(path));
  Fingerprint now = described.fingerprint;
  if (const auto* start = StartPart(stored)) now.push_back(*start);
  CheckProblemFingerprint(stored.fingerprint, now, path, stored.combabc_version, CombabcVersion());
  const auto limits = ApplyStopLimits(stored.stop_limits, request.limits, options);
  CheckContinuation(stored, options, finished, request.names, path);
  return BeginResumeOnAll(executor, &*store, path, limits);
}

}  // namespace

RunMetadata DescribeProblem(const ProblemRunRequest& request) {
  const SmcProblem& problem = request.problem;
  const SmcOptions& options = request.options;
  RunMetadata m = StampedMetadata();
  m.seed = options.seed;
  m.threads = options.threads;
  m.estimator = ToString(options.estimator);
  const BinarySpace& bits = problem.space->binary();
  m.dimension = bits.dimension();
  for (int k = 0; k < m.dimension; ++k) m.bit_names.push_back(bits.name(k));
  m.bit_prior_one = bits.bit_prior_one();
  m.distance_components = problem.distance->components();
  m.reals = problem.space->reals();
  m.proposal = options.proposal;
  m.tempering_form = ToString(options.tempering.form);
  if (request.positions.empty()) {
    m.position_unit = "index";
    for (std::size_t i = 0; i < request.observed.size(); ++i) {
      m.output_positions.push_back(static_cast<double>(i));
    }
  } else {
    m.position_unit = request.position_unit;
    m.output_positions = request.positions;
  }
  m.measured.positions = m.output_positions;
  m.measured.values = request.observed;
  ProblemFingerprintInputs inputs;
  inputs.options = &options;
  inputs.space = problem.space;
  inputs.observed = request.observed;
  inputs.positions = request.positions;
  inputs.components = m.distance_components;
  inputs.calling = request.calling;
  inputs.low_fidelity = problem.low_fidelity != nullptr;
  inputs.version = CombabcVersion();
  m.fingerprint = ComputeProblemFingerprint(inputs);
  return m;
}

RunOutcome RunProblem(const ProblemRunRequest& request, SmcObserver* progress) {
  const std::string& path = request.history_path;
  if (path.empty() && (request.resume || request.report || !request.start_from.empty())) {
    throw Error(ErrorKind::kUsage, "resume, report and start_from need a history file");
  }
  SmcOptions options = request.options;
  SmcProblem problem = request.problem;
  std::unique_ptr<Executor> executor;
  if (problem.executor == nullptr) {
    executor = std::make_unique<ThreadPoolExecutor>(options.threads);
    problem.executor = executor.get();
  }
  RunMetadata metadata = DescribeProblem(request);
  std::optional<HistoryStore> store;
  std::optional<ResumePoint> resume;
  std::optional<StartPopulation> start;
  if (request.resume) {
    resume = BeginProblemResume(request, metadata, options, *problem.executor, store);
  } else {
    if (!request.start_from.empty()) {
      start =
          StartFromFinishedRun(request.start_from, *problem.space, problem.distance->components());
      problem.start = &*start;
      metadata.fingerprint.push_back(StartFingerprint(request.start_from));
    }
    if (!path.empty()) {
      if (request.report) CheckReportPossible(ReportDirectory(path));
      store.emplace(HistoryStore::Create(path, metadata, request.overwrite));
    }
  }
  RunOutcome outcome = Execute({.problem = problem,
                                .options = &options,
                                .store = store ? &*store : nullptr,
                                .history_path = path,
                                .resume = resume ? &*resume : nullptr,
                                .report = request.report,
                                .report_progress = {},
                                .on_checks_before = {}},
                               progress);
  if (!store) {
    // No history to read the answer back from: the same function on the metadata the history
    // would hold (its termination recorded as HistoryStore::Finish records it) and the run as it
    // ended, so that a run without a file answers as one with a file would.
    metadata.termination = ToString(outcome.history.summary.termination);
    outcome.answer = SummariseAnswer(metadata, outcome.history, BitPositions(metadata));
  }
  return outcome;
}

}  // namespace combabc::services
