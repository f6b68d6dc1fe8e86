#include "combabc/services/run.hpp"

#include <algorithm>
#include <filesystem>
#include <functional>
#include <optional>
#include <utility>

#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/services/report.hpp"
#include "services/steps/output_folders.hpp"
#include "services/steps/problem.hpp"
#include "services/steps/report_checks.hpp"
#include "services/steps/run_fingerprint.hpp"
#include "services/steps/run_steps.hpp"
#include "services/steps/start_from.hpp"
#include "services/steps/worker_steps.hpp"

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

// The problem rebuilt as the stored fingerprint reads its config, when that is a legacy reading
// (LegacyReading: a sensor run written before RZT became the default), so that it resumes as the
// run it was. Returns the fingerprint of p as rebuilt.
Fingerprint RebuildAsStored(Problem& p, const Fingerprint& stored, const std::string& path) {
  Fingerprint now = FingerprintOf(p);
  std::optional<CalibrationConfig> legacy =
      LegacyReading(p.config, now, stored, [&](const CalibrationConfig& config) {
        return FingerprintOf(p, &config);
      });
  if (!legacy) return now;
  Problem old;
  old.config = std::move(*legacy);
  old.data = p.data;
  old.executor = std::move(p.executor);
  BuildModel(old, path);
  p = std::move(old);
  return FingerprintOf(p);
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
  return Execute({.problem = p.view(),
                  .options = &p.config.smc,
                  .store = store ? &*store : nullptr,
                  .history_path = history_path,
                  .resume = nullptr,
                  .report = request.report,
                  .report_progress = request.on_report_progress,
                  .on_checks_before = request.on_checks_before},
                 progress);
}

RunOutcome ResumeCalibration(const ResumeRequest& request, SmcObserver* progress) {
  const std::string& history_path = request.history_path;
  // Read-only first: with a distributed executor every worker reads the run, and only the
  // primary, once known, locks and rewrites it.
  const auto metadata = HistoryStore::Open(history_path, true).LoadMetadata();
  const bool finished = CheckResumable(metadata, request.limits, request.names, history_path);
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
  std::optional<HistoryStore> store;
  OnPrimary(*p.executor, [&] {
    if (request.report) CheckReportPossible(ReportDirectory(history_path));
    store.emplace(HistoryStore::Open(history_path));
  });
  BuildModel(p, history_path);
  Fingerprint now = RebuildAsStored(p, metadata.fingerprint, history_path);
  CheckStoredExperiments(metadata.experiments, ExperimentsOf(p), history_path);
  // A run that started from a finished one (--from) keeps that part: its wave 0 holds the start.
  if (const auto* start = StartPart(metadata)) now.push_back(*start);
  // The rebuilt problem must be the one the run started with, or the continuation would not
  // equal an uninterrupted run. Checked before BeginResume rewrites anything, and over the config
  // as written: the stop limits below are not part of the run's identity.
  CheckResumeFingerprint(metadata.fingerprint,
                         now,
                         history_path,
                         DataSources(p.config),
                         metadata.combabc_version,
                         CombabcVersion(),
                         p.simulator.handshake);
  const auto limits = ApplyStopLimits(metadata.stop_limits, request.limits, p.config.smc);
  CheckContinuation(metadata, p.config.smc, finished, request.names, history_path);
  const ResumePoint resume =
      BeginResumeOnAll(*p.executor, store ? &*store : nullptr, history_path, limits);
  return Execute({.problem = p.view(),
                  .options = &p.config.smc,
                  .store = store ? &*store : nullptr,
                  .history_path = history_path,
                  .resume = &resume,
                  .report = request.report,
                  .report_progress = request.on_report_progress,
                  .on_checks_before = request.on_checks_before},
                 progress);
}

}  // namespace combabc::services
