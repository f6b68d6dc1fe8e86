#include "combabc/services/run.hpp"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <optional>
#include <utility>

#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/services/report.hpp"
#include "services/fan_out_observer.hpp"
#include "services/output_folders.hpp"
#include "services/problem.hpp"
#include "services/read_back.hpp"
#include "services/report_checks.hpp"
#include "services/run_fingerprint.hpp"
#include "services/start_from.hpp"
#include "services/worker_steps.hpp"

#ifndef COMBABC_VERSION
#define COMBABC_VERSION "unknown"
#endif

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

// The experiments' data files, for messages.
std::string DataSources(const CalibrationConfig& c) {
  std::string text;
  for (const ExperimentConfig& x : c.experiments) {
    text += (text.empty() ? "" : ", ") + x.data.csv;
  }
  return text;
}

// The history's experiment table must be what its configuration gives: the data were split by it
// (StoredProfiles), and export and report name and slice the experiments by it. The fingerprint
// does not cover it, so a table that disagrees (a crafted or damaged history) would resume and
// report its experiments under the wrong names or slices.
void CheckStoredExperiments(const std::vector<StoredExperiment>& stored,
                            const std::vector<StoredExperiment>& now,
                            const std::string& path) {
  for (std::size_t e = 0; e < stored.size() && e < now.size(); ++e) {
    const StoredExperiment& a = stored[e];
    const StoredExperiment& b = now[e];
    std::string field, before, after;
    auto differs = [&](const char* key, const std::string& x, const std::string& y) {
      if (!field.empty() || x == y) return;
      field = key;
      before = x;
      after = y;
    };
    differs("name", Excerpt(a.name), Excerpt(b.name));
    // A history from before the table (schema v1 to v5) is upgraded with one unnamed experiment
    // without a description (docs/history.md, "Integrity"): its counts are what can be checked.
    const bool upgraded = stored.size() == 1 && a.name.empty() && a.description.empty();
    if (!upgraded) differs("description", Excerpt(a.description), Excerpt(b.description));
    differs("outputs", std::to_string(a.outputs), std::to_string(b.outputs));
    differs("measured points", std::to_string(a.measured), std::to_string(b.measured));
    differs("components", std::to_string(a.components), std::to_string(b.components));
    if (field.empty()) continue;
    std::string message =
        "resume: the history's experiment table disagrees with its configuration: experiment ";
    message += std::to_string(e + 1);
    message += "'s " + field + " is ";
    message += before;
    message += " in the table and ";
    message += after;
    message += " as this combabc reads the configuration; start a new run";
    throw Error(ErrorKind::kConfig, message, path);
  }
}

// The history store's callbacks, made on the primary only (`store` is null elsewhere) and joined
// after each, so that a failed write (disk full) stops every worker at the same callback instead
// of leaving the others waiting in the next batch.
class PrimaryStore : public SmcObserver {
 public:
  PrimaryStore(Executor& executor, HistoryStore* store) : executor_(executor), store_(store) {}
  void OnWaveStart(const WaveRecord& wave) override {
    OnPrimary(executor_, [&] { store_->OnWaveStart(wave); });
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    OnPrimary(executor_, [&] { store_->OnBatch(progress, accepted); });
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    OnPrimary(executor_, [&] { store_->OnWaveEnd(wave); });
  }

 private:
  Executor& executor_;
  HistoryStore* store_;
};

// On the primary, when the first wave has ended (after the store checkpointed it and the progress
// display printed its line): the checks before sampling, from the wave as stored, so that they
// are the numbers the end of the run and the export compute.
class BeforeChecks : public SmcObserver {
 public:
  BeforeChecks(HistoryStore* store, std::function<void(const FitChecks&)> report)
      : store_(store), report_(std::move(report)) {}
  void OnWaveEnd(const WaveRecord& wave) override {
    if (store_ == nullptr || !report_ || wave.wave != 0) return;
    FitChecks checks;
    try {
      const RunHistory stored = store_->LoadHistory();
      const RunMetadata metadata = store_->LoadMetadata();
      checks = ComputeBeforeChecks(
          metadata, stored.waves.empty() ? nullptr : &stored.waves.front(), CheckOptions(metadata));
    } catch (const Error& e) {
      // Warnings, never an error: the end of the run says it again.
      checks.before.push_back(
          {"note",
           "checks_failed",
           std::string("the checks before sampling could not read the history: ") + e.what()});
    }
    report_(checks);
  }

 private:
  HistoryStore* store_;
  std::function<void(const FitChecks&)> report_;
};

// The same parts with the same digests, in any order (the history stores them sorted).
bool SameFingerprint(Fingerprint a, Fingerprint b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  return a == b;
}

// `store` is the history on the primary, null on the other workers of a distributed executor.
RunOutcome Execute(Problem& problem,
                   HistoryStore* store,
                   const std::string& history_path,
                   const ResumePoint* resume,
                   bool report,
                   const ReportProgress& report_progress,
                   SmcObserver* progress,
                   const std::function<void(const FitChecks&)>& on_checks_before) {
  Executor& executor = *problem.executor;
  PrimaryStore stored(executor, store);
  BeforeChecks before(store, on_checks_before);
  FanOutObserver observer({&stored, progress, &before});
  RunOutcome outcome;
  outcome.history_path = history_path;
  try {
    outcome.history = RunCombinatorialSmc(problem.view(), problem.config.smc, &observer, resume);
  } catch (const std::exception& e) {
    try {
      if (store) store->MarkFailed(e.what());
    } catch (const std::exception&) {
      // The store itself may be what failed (disk full); the first error is the one to report.
    }
    throw;
  }
  OnPrimary(executor, [&] {
    store->Finish(outcome.history.summary);
    // From the stored history: a resumed run's earlier waves count too.
    ReadBack back = ReadBackHistory(*store);
    outcome.checks = std::move(back.checks);
    outcome.answer = std::move(back.answer);
    outcome.strip = std::move(back.strip);
    if (!report) return;
    try {
      outcome.report_directory =
          WriteReport(store->path(), ReportDirectory(store->path()), false, report_progress);
    } catch (const Error& e) {
      // One line still, but saying that the run itself is safe and how to retry the report.
      throw Error(e.kind(),
                  "the run is saved in " + store->path() +
                      " ('combabc report' retries the report), " +
                      "but its report failed: " + e.what());
    }
  });
  return outcome;
}

// The terminations a raised limit can continue from (docs/history.md, "Resume").
bool StoppedOnLimit(const RunMetadata& m) {
  const auto t = ParseEnum<Termination>(m.termination);
  return t && (*t == Termination::kBudgetExhausted || *t == Termination::kWallTimeExceeded ||
               *t == Termination::kAcceptanceRateTooLow || *t == Termination::kTooManyFailures);
}

// Shortest round-trip text, as the config would say it (0.6, not 0.59999999999999998).
std::string LimitText(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

// Sets `smc`'s stop limits from those an earlier resume recorded, then from `given`; returns
// every limit set this way as (key, value) text, to record in the history.
std::vector<std::pair<std::string, std::string>> ApplyStopLimits(
    const std::vector<std::pair<std::string, std::string>>& recorded,
    const StopLimits& given,
    SmcOptions& smc) {
  std::vector<std::pair<std::string, std::string>> limits;
  auto set = [&](const std::string& key, const std::string& value) {
    // The history's text, or ours: written by BeginResume from LimitText or std::to_string.
    if (key == "max_simulations") {
      smc.max_simulations = std::strtoll(value.c_str(), nullptr, 10);
    } else if (key == "max_wall_time") {
      smc.max_wall_time_s = std::strtod(value.c_str(), nullptr);
    } else if (key == "min_acceptance_rate") {
      smc.min_acceptance_rate = std::strtod(value.c_str(), nullptr);
    } else if (key == "max_failure_fraction") {
      smc.max_failure_fraction = std::strtod(value.c_str(), nullptr);
    } else {
      return;  // a key a later combabc may record; this one does not know it
    }
    std::erase_if(limits, [&](const auto& kv) { return kv.first == key; });
    limits.emplace_back(key, value);
  };
  for (const auto& [key, value] : recorded) set(key, value);
  if (given.max_simulations) set("max_simulations", std::to_string(*given.max_simulations));
  if (given.max_wall_time_s) set("max_wall_time", LimitText(*given.max_wall_time_s));
  if (given.min_acceptance_rate) set("min_acceptance_rate", LimitText(*given.min_acceptance_rate));
  if (given.max_failure_fraction) {
    set("max_failure_fraction", LimitText(*given.max_failure_fraction));
  }
  std::string why;
  if (!smc.IsValid(&why)) throw Error(ErrorKind::kUsage, "resume: " + why);
  std::sort(limits.begin(), limits.end());
  return limits;
}

}  // namespace

RunOutcome RunCalibration(const RunRequest& request, SmcObserver* progress) {
  OutputFolders folders;  // outlives the problem: its simulator may work inside them
  Problem p;
  LoadProblem(request.config_path, request.threads, p, request.config_text);
  MakeExecutor(p, request.executor);

  std::string directory = request.output_directory.empty()
                              ? ResolvePath(p.config.directory, p.config.output.directory)
                              : request.output_directory;
  const std::string history_path = (fs::path(directory) / p.config.output.database).string();
  if (request.on_history_path) request.on_history_path(history_path);
  OnPrimary(*p.executor, [&] {
    if (request.report) CheckReportPossible(ReportDirectory(history_path));
    folders.Create(directory);
  });
  BuildModelIn(p, history_path);
  RunMetadata metadata = Describe(p);
  if (!request.start_from.empty()) {
    p.start = StartFromFinishedRun(request.start_from, p);
    metadata.fingerprint.push_back(StartFingerprint(request.start_from));
  }
  std::optional<HistoryStore> store;
  OnPrimary(*p.executor, [&] {
    store.emplace(HistoryStore::Create(history_path, metadata, request.overwrite));
    folders.Keep();
  });
  return Execute(p,
                 store ? &*store : nullptr,
                 history_path,
                 nullptr,
                 request.report,
                 request.on_report_progress,
                 progress,
                 request.on_checks_before);
}

std::string LimitOption(Termination stop) {
  switch (stop) {
    case Termination::kBudgetExhausted:
      return "--max-simulations";
    case Termination::kAcceptanceRateTooLow:
      return "--min-acceptance-rate";
    case Termination::kTooManyFailures:
      return "--max-failure-fraction";
    default:
      return "--max-wall-time";
  }
}

RunOutcome ResumeCalibration(const ResumeRequest& request, SmcObserver* progress) {
  const std::string& history_path = request.history_path;
  // Read-only first: with a distributed executor every worker reads the run, and only the
  // primary, once known, locks and rewrites it.
  const auto metadata = HistoryStore::Open(history_path, true).LoadMetadata();
  const bool stopped = metadata.status == RunStatus::kFinished && StoppedOnLimit(metadata);
  if (metadata.status == RunStatus::kFinished && !stopped) {
    throw Error(ErrorKind::kUsage,
                "the run has already finished (" + metadata.termination +
                    "); nothing to resume. Use 'combabc report' or 'combabc export'",
                history_path);
  }
  if (metadata.config_text.empty()) {
    // A run of a Python problem (combabc.run(problem, output_directory=...)): no config to
    // rebuild it from; Python passes its simulator again.
    throw Error(ErrorKind::kUsage,
                "the run's simulator is written in Python: resume it from Python, "
                "combabc.resume(path, problem, options)",
                history_path);
  }
  Problem p;
  p.config = ParseConfig(metadata.config_text, metadata.config_path);
  if (request.threads >= 0) p.config.smc.threads = request.threads;
  // The measured data as the run first used them, not as the CSV reads today.
  p.data = StoredProfiles(metadata, history_path);
  if (p.data.size() != p.config.experiments.size()) {
    throw Error(ErrorKind::kConfig,
                "resume: the run has " + std::to_string(p.data.size()) +
                    " experiments and its configuration now reads as " +
                    std::to_string(p.config.experiments.size()) + "; start a new run",
                history_path);
  }
  MakeExecutor(p, request.executor);
  // Whatever would refuse the resume without looking at the model is checked before the model is
  // built (seconds): the report folder, and the writer's lock (another process resuming the run)
  // with the history's checks, taken now and held. Nothing is written before BeginResume.
  const bool report = request.report;
  std::optional<HistoryStore> store;
  OnPrimary(*p.executor, [&] {
    if (report) CheckReportPossible(ReportDirectory(history_path));
    store.emplace(HistoryStore::Open(history_path));
  });
  BuildModel(p, history_path);
  // A sensor run written before RZT became the default (combabc before 2026-11-23) has no
  // [model] theory in its config because it was Kirchhoff then: its stored
  // fingerprint says so, and it resumes as the run it was (its finished waves stay usable).
  // The model is rebuilt only when that reading is the one the fingerprint matches.
  Fingerprint now = FingerprintOf(p);
  if (p.config.simulator.kind == SimulatorKind::kSensor &&
      p.config.model.theory == plate::PlateTheory::kRzt &&
      !SameFingerprint(now, metadata.fingerprint)) {
    CalibrationConfig kirchhoff = p.config;
    kirchhoff.model.theory = plate::PlateTheory::kKirchhoff;
    if (SameFingerprint(FingerprintOf(p, &kirchhoff), metadata.fingerprint)) {
      Problem old;
      old.config = std::move(kirchhoff);
      old.data = p.data;
      old.executor = std::move(p.executor);
      BuildModel(old, history_path);
      p = std::move(old);
      now = FingerprintOf(p);
    }
  }
  CheckStoredExperiments(metadata.experiments, ExperimentsOf(p), history_path);
  // A run that started from a finished one (--from) keeps that part: its wave 0 holds the start.
  const auto start = std::find_if(metadata.fingerprint.begin(),
                                  metadata.fingerprint.end(),
                                  [](const auto& part) { return part.first == "start"; });
  if (start != metadata.fingerprint.end()) now.push_back(*start);
  // The rebuilt problem must be the one the run started with, or the continuation would not
  // equal an uninterrupted run. Checked before BeginResume rewrites anything, and over the config
  // as written: the stop limits below are not part of the run's identity.
  CheckResumeFingerprint(metadata.fingerprint,
                         now,
                         history_path,
                         DataSources(p.config),
                         metadata.combabc_version,
                         COMBABC_VERSION,
                         p.simulator.handshake);
  const auto limits = ApplyStopLimits(metadata.stop_limits, request.limits, p.config.smc);
  if (stopped) {
    // Resuming would only record the same stop again: say which limit to raise instead.
    const ResumePoint point = HistoryStore::Open(history_path, true).LoadResumePoint();
    if (const auto stop = ImmediateStop(p.config.smc, point)) {
      throw Error(ErrorKind::kUsage,
                  "resume: the run stopped (" + std::string(ToString(stop->first)) + ": " +
                      stop->second + ") and would stop again at once; raise the limit with " +
                      LimitOption(stop->first),
                  history_path);
    }
  }
  if (start != metadata.fingerprint.end() &&
      HistoryStore::Open(history_path, true).LoadResumePoint().completed.empty()) {
    // Its wave 0 (the finished run's posterior, re-simulated) was cut short: the population it
    // started from is not in this history.
    throw Error(ErrorKind::kUsage,
                "resume: the run started from a finished run (--from) and stopped before its "
                "first wave was stored; start it again with 'combabc run CONFIG --from RUN.sqlite'",
                history_path);
  }
  ResumePoint resume;
  OnPrimary(*p.executor, [&] { resume = store->BeginResume(limits); });
  // The other workers read the resume point as the primary's BeginResume left it, before the
  // primary writes anything more (the second join).
  std::exception_ptr error;
  if (!p.executor->primary()) {
    try {
      resume = HistoryStore::Open(history_path, true).LoadResumePoint();
    } catch (...) {
      error = std::current_exception();
    }
  }
  p.executor->Join(error);
  return Execute(p,
                 store ? &*store : nullptr,
                 history_path,
                 &resume,
                 report,
                 request.on_report_progress,
                 progress,
                 request.on_checks_before);
}

}  // namespace combabc::services
