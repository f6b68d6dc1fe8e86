#include "services/steps/run_steps.hpp"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <exception>

#include "combabc/core/error.hpp"
#include "services/steps/fan_out_observer.hpp"
#include "services/steps/read_back.hpp"
#include "services/steps/report_checks.hpp"
#include "services/steps/worker_steps.hpp"

namespace combabc::services {
namespace {

// The history store's callbacks, made on the primary only (`store` is null elsewhere, and for a
// run without a history) and joined after each, so that a failed write (disk full) stops every
// worker at the same callback instead of leaving the others waiting in the next batch.
class PrimaryStore : public SmcObserver {
 public:
  PrimaryStore(Executor& executor, HistoryStore* store) : executor_(executor), store_(store) {}
  void OnWaveStart(const WaveRecord& wave) override {
    OnPrimary(executor_, [&] {
      if (store_) store_->OnWaveStart(wave);
    });
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    OnPrimary(executor_, [&] {
      if (store_) store_->OnBatch(progress, accepted);
    });
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    OnPrimary(executor_, [&] {
      if (store_) store_->OnWaveEnd(wave);
    });
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

// The terminations a raised limit can continue from (docs/history.md, "Resume").
bool StoppedOnLimit(Termination t) {
  return t == Termination::kBudgetExhausted || t == Termination::kWallTimeExceeded ||
         t == Termination::kAcceptanceRateTooLow || t == Termination::kTooManyFailures;
}

// Shortest round-trip text, as the config would say it (0.6, not 0.59999999999999998).
std::string LimitText(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

// More waves continue a run as if it had planned them from the start, unless the planned number
// shaped the waves it did: a linear tempering schedule falls to 0 at the last planned wave, and
// an adaptive multi-fidelity run does not tune after its last one.
void CheckMoreWaves(const RunMetadata& metadata,
                    const SmcOptions& options,
                    OptionNames names,
                    const std::string& path) {
  std::string why;
  if (options.tempering.kind == TemperingKind::kLinear) {
    why = "its linear tempering planned phi over its waves";
  }
  const bool low_fidelity =
      std::any_of(metadata.fingerprint.begin(), metadata.fingerprint.end(), [](const auto& part) {
        return part.first == "low_fidelity";
      });
  if (low_fidelity && options.multi_fidelity.adapt) {
    why = "its multi-fidelity probabilities were not tuned after its last wave";
  }
  if (why.empty()) return;
  throw Error(ErrorKind::kUsage,
              "resume: more waves would not continue the run as one longer run (" + why +
                  "); start a new run with " + (names == OptionNames::kCli ? "[sampler] " : "") +
                  "waves = N",
              path);
}

}  // namespace

std::string LimitOption(Termination stop, OptionNames names) {
  const bool cli = names == OptionNames::kCli;
  switch (stop) {
    case Termination::kBudgetExhausted:
      return cli ? "--max-simulations" : "max_simulations=";
    case Termination::kAcceptanceRateTooLow:
      return cli ? "--min-acceptance-rate" : "min_acceptance_rate=";
    case Termination::kTooManyFailures:
      return cli ? "--max-failure-fraction" : "max_failure_fraction=";
    case Termination::kMaxWaves:
      return cli ? "--waves" : "waves=";
    default:
      return cli ? "--max-wall-time" : "max_wall_time=";
  }
}

RunOutcome Execute(const Execution& run, SmcObserver* progress) {
  Executor& executor = *run.problem.executor;
  HistoryStore* store = run.store;
  PrimaryStore stored(executor, store);
  BeforeChecks before(store, run.on_checks_before);
  FanOutObserver observer({&stored, progress, &before});
  RunOutcome outcome;
  outcome.history_path = run.history_path;
  try {
    outcome.history = RunCombinatorialSmc(run.problem, *run.options, &observer, run.resume);
  } catch (const std::exception& e) {
    try {
      if (store) store->MarkFailed(e.what());
    } catch (const std::exception&) {
      // The store itself may be what failed (disk full); the first error is the one to report.
    }
    throw;
  }
  OnPrimary(executor, [&] {
    if (!store) return;
    store->Finish(outcome.history.summary);
    // From the stored history: a resumed run's earlier waves count too.
    ReadBack back = ReadBackHistory(*store);
    outcome.checks = std::move(back.checks);
    outcome.answer = std::move(back.answer);
    outcome.strip = std::move(back.strip);
    if (!run.report) return;
    try {
      outcome.report_directory =
          WriteReport(store->path(), ReportDirectory(store->path()), false, run.report_progress);
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

bool CheckResumable(const RunMetadata& metadata,
                    const StopLimits& limits,
                    OptionNames names,
                    const std::string& path) {
  if (metadata.status != RunStatus::kFinished) return false;
  const auto t = ParseEnum<Termination>(metadata.termination);
  if (t && StoppedOnLimit(*t)) return true;
  if (t == Termination::kMaxWaves && limits.num_waves) return true;
  std::string message = "the run has already finished (" + metadata.termination + ")";
  if (names == OptionNames::kCli) {
    message += "; nothing to resume. Use 'combabc report' or 'combabc export'";
    if (t == Termination::kMaxWaves) message += "; or give it more waves: --waves N";
  } else {
    message += "; nothing to resume";
    if (t == Termination::kMaxWaves) message += ": give it more waves with waves=N";
  }
  throw Error(ErrorKind::kUsage, message, path);
}

std::vector<std::pair<std::string, std::string>> ApplyStopLimits(
    const std::vector<std::pair<std::string, std::string>>& recorded,
    const StopLimits& given,
    SmcOptions& options) {
  std::vector<std::pair<std::string, std::string>> limits;
  auto set = [&](const std::string& key, const std::string& value) {
    // The history's text, or ours: written by BeginResume from LimitText or std::to_string.
    if (key == "max_simulations") {
      options.max_simulations = std::strtoll(value.c_str(), nullptr, 10);
    } else if (key == "max_wall_time") {
      options.max_wall_time_s = std::strtod(value.c_str(), nullptr);
    } else if (key == "min_acceptance_rate") {
      options.min_acceptance_rate = std::strtod(value.c_str(), nullptr);
    } else if (key == "max_failure_fraction") {
      options.max_failure_fraction = std::strtod(value.c_str(), nullptr);
    } else if (key == "waves") {
      options.num_waves = static_cast<int>(std::strtol(value.c_str(), nullptr, 10));
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
  if (given.num_waves) set("waves", std::to_string(*given.num_waves));
  std::string why;
  if (!options.IsValid(&why)) throw Error(ErrorKind::kUsage, "resume: " + why);
  std::sort(limits.begin(), limits.end());
  return limits;
}

void CheckContinuation(const RunMetadata& metadata,
                       const SmcOptions& options,
                       bool finished,
                       OptionNames names,
                       const std::string& path) {
  const bool more_waves = std::any_of(metadata.stop_limits.begin(),
                                      metadata.stop_limits.end(),
                                      [](const auto& kv) { return kv.first == "waves"; }) ||
                          metadata.termination == ToString(Termination::kMaxWaves);
  if (finished) {
    // Resuming would only record the same stop again: say which limit to raise instead.
    const ResumePoint point = HistoryStore::Open(path, true).LoadResumePoint();
    const int done = static_cast<int>(point.completed.size());
    if (metadata.termination == ToString(Termination::kMaxWaves) && options.num_waves <= done) {
      throw Error(ErrorKind::kUsage,
                  "resume: the run has done its " + std::to_string(done) +
                      " waves and would stop again at once; give it more with " +
                      LimitOption(Termination::kMaxWaves, names) + " above " + std::to_string(done),
                  path);
    }
    if (const auto stop = ImmediateStop(options, point)) {
      const std::string option = LimitOption(stop->first, names);
      throw Error(ErrorKind::kUsage,
                  "resume: the run stopped (" + std::string(ToString(stop->first)) + ": " +
                      stop->second + ") and would stop again at once; raise the limit with " +
                      option,
                  path);
    }
  }
  if (more_waves) CheckMoreWaves(metadata, options, names, path);
  if (StartPart(metadata) != nullptr &&
      HistoryStore::Open(path, true).LoadResumePoint().completed.empty()) {
    // Its wave 0 (the finished run's posterior, re-simulated) was cut short: the population it
    // started from is not in this history.
    throw Error(ErrorKind::kUsage,
                names == OptionNames::kCli
                    ? "resume: the run started from a finished run (--from) and stopped before "
                      "its first wave was stored; start it again with 'combabc run CONFIG --from "
                      "RUN.sqlite'"
                    : "resume: the run started from a finished run (start_from=) and stopped "
                      "before its first wave was stored; start it again with combabc.run(..., "
                      "start_from=...)",
                path);
  }
}

ResumePoint BeginResumeOnAll(Executor& executor,
                             HistoryStore* store,
                             const std::string& path,
                             const std::vector<std::pair<std::string, std::string>>& limits) {
  ResumePoint resume;
  OnPrimary(executor, [&] { resume = store->BeginResume(limits); });
  // The other workers read the resume point as the primary's BeginResume left it, before the
  // primary writes anything more (the second join).
  std::exception_ptr error;
  if (!executor.primary()) {
    try {
      resume = HistoryStore::Open(path, true).LoadResumePoint();
    } catch (...) {
      error = std::current_exception();
    }
  }
  executor.Join(error);
  return resume;
}

const std::pair<std::string, std::string>* StartPart(const RunMetadata& metadata) {
  const auto start = std::find_if(metadata.fingerprint.begin(),
                                  metadata.fingerprint.end(),
                                  [](const auto& part) { return part.first == "start"; });
  return start != metadata.fingerprint.end() ? &*start : nullptr;
}

}  // namespace combabc::services
