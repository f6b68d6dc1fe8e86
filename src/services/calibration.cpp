#include "combabc/services/calibration.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <thread>

#include "combabc/config/distance_from_config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/metrics/joint_distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/enumeration.hpp"
#include "services/fan_out_observer.hpp"
#include "services/report_checks.hpp"
#include "services/run_fingerprint.hpp"
#include "services/simulator_factory.hpp"

#ifndef COMBABC_GIT_HASH
#define COMBABC_GIT_HASH ""
#endif
#ifndef COMBABC_VERSION
#define COMBABC_VERSION "unknown"
#endif

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

// Everything a run needs besides its history: built identically for a new run and a resume,
// which is what makes a resumed history equal to an uninterrupted one.
struct Problem {
  CalibrationConfig config;
  std::vector<MeasuredProfile> data;  // one per experiment, as the metric compares them
  std::unique_ptr<JointDistance> distance;
  std::optional<ParameterSpace> space;
  std::unique_ptr<Executor> executor;
  BuiltSimulator simulator;  // last: external processes end before anything else goes

  SmcProblem view() const {
    SmcProblem v{&*space, simulator.simulator.get(), distance.get()};
    v.executor = executor.get();
    return v;
  }
};

// "load at 0.45 m (y 0.5 of the width), 0.04 N, 5 Hz; scan 0-0.9 m at y 0.5": what a report
// titles the experiment's panels with.
std::string ExperimentDescription(const CalibrationConfig& c, const ExperimentConfig& x) {
  char text[200];
  if (c.simulator.kind != SimulatorKind::kSensor) {
    if (x.line == 0) return "";
    std::snprintf(text,
                  sizeof text,
                  "load at %g m (y %g of the width), %g N, %g Hz",
                  x.load.load_x,
                  x.load.load_y_fraction,
                  x.load.load_force,
                  x.frequency_hz);
    return text;
  }
  const std::vector<double>& out = x.load.output_positions;
  std::snprintf(text,
                sizeof text,
                "load at %g m (y %g of the width), %g N, %g Hz; scan %g-%g m at y %g",
                x.load.load_x,
                x.load.load_y_fraction,
                x.load.load_force,
                x.frequency_hz,
                out.front(),
                out.back(),
                x.load.output_y_fraction);
  return text;
}

// The experiments' data files, for messages.
std::string DataSources(const CalibrationConfig& c) {
  std::string text;
  for (const ExperimentConfig& x : c.experiments) {
    text += (text.empty() ? "" : ", ") + x.data.csv;
  }
  return text;
}

// The measured profiles a history recorded, one per experiment.
std::vector<MeasuredProfile> StoredProfiles(const RunMetadata& m, const std::string& path) {
  std::vector<MeasuredProfile> profiles;
  std::size_t begin = 0;
  for (const StoredExperiment& x : m.experiments) {
    const auto end = begin + static_cast<std::size_t>(x.measured);
    if (end > m.measured.positions.size()) {
      throw Error(
          ErrorKind::kData, "the experiments' measured points exceed the stored ones", path);
    }
    MeasuredProfile profile;
    profile.positions.assign(m.measured.positions.begin() + static_cast<std::ptrdiff_t>(begin),
                             m.measured.positions.begin() + static_cast<std::ptrdiff_t>(end));
    profile.values.assign(m.measured.values.begin() + static_cast<std::ptrdiff_t>(begin),
                          m.measured.values.begin() + static_cast<std::ptrdiff_t>(end));
    profiles.push_back(std::move(profile));
    begin = end;
  }
  return profiles;
}

// The executor for the problem's threads (after LoadProblem or the resume's config).
void MakeExecutor(Problem& p, const ExecutorFactory& factory) {
  p.executor = factory ? factory(p.config.smc.threads)
                       : std::make_unique<ThreadPoolExecutor>(p.config.smc.threads);
}

// Runs `step` on the primary only, then joins: its failure is thrown on every worker.
template <typename Step>
void OnPrimary(Executor& executor, Step&& step) {
  std::exception_ptr error;
  if (executor.primary()) {
    try {
      step();
    } catch (...) {
      error = std::current_exception();
    }
  }
  executor.Join(error);
}

// Runs `step` on every worker, then joins: one worker's failure is thrown on all.
template <typename Step>
void OnEvery(Executor& executor, Step&& step) {
  std::exception_ptr error;
  try {
    step();
  } catch (...) {
    error = std::current_exception();
  }
  executor.Join(error);
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

// history_path: the run's history file; an external simulator works in a folder beside it.
void BuildModel(Problem& p, const std::string& history_path) {
  // First, as it is cheap: checks the metric's windows and indicators against the simulator's
  // output coordinates and the data before the model is built or anything simulated or stored.
  if (!p.distance) p.distance = MakeDistance(p.config, p.data);
  p.simulator = MakeSimulator(p.config, WorkDirectoryOf(history_path), p.executor->thread_pool());
  p.space.emplace(BinarySpace(p.config.space), p.config.reals);
}

// The run's output folder and whichever of its parents were missing, created on the primary and
// removed again (those still empty, deepest first) unless Keep() is called once the history
// exists: a run that fails before it has written anything leaves no folder behind.
class OutputFolders {
 public:
  OutputFolders() = default;
  OutputFolders(const OutputFolders&) = delete;
  OutputFolders& operator=(const OutputFolders&) = delete;
  ~OutputFolders() {
    std::error_code ec;
    for (const fs::path& folder : created_) fs::remove(folder, ec);  // only if empty
  }

  void Create(const std::string& directory) {
    std::error_code ec;
    for (fs::path folder = directory; !folder.empty() && !fs::exists(folder, ec);
         folder = folder.parent_path()) {
      created_.push_back(folder);
      if (folder == folder.parent_path()) break;
    }
    fs::create_directories(directory, ec);
    if (ec) {
      throw Error(
          ErrorKind::kCantCreate, "cannot create output directory: " + ec.message(), directory);
    }
  }
  void Keep() { created_.clear(); }

 private:
  std::vector<fs::path> created_;  // deepest first
};

// Builds the model on every worker once the output folder exists (an external simulator works
// inside it).
void BuildModelIn(Problem& p, const std::string& history_path) {
  OnEvery(*p.executor, [&] { BuildModel(p, history_path); });
}

// `config` defaults to the problem's own; resume also asks what another reading of it would give.
Fingerprint FingerprintOf(const Problem& p, const CalibrationConfig* config = nullptr) {
  FingerprintInputs inputs;
  inputs.config = config != nullptr ? config : &p.config;
  inputs.space = &*p.space;
  inputs.data = p.data;
  inputs.components = p.distance->components();
  inputs.version = COMBABC_VERSION;
  inputs.handshake = p.simulator.handshake;
  return ComputeFingerprint(inputs);
}

// The same parts with the same digests, in any order (the history stores them sorted).
bool SameFingerprint(Fingerprint a, Fingerprint b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  return a == b;
}

// A new run's problem from its config file: the config (threads >= 0 overrides the config's), the
// measured data read from disk and the metric; BuildModelIn follows once the output folder
// exists. (A resume takes the data stored in its history.)
void LoadProblem(const std::string& config_path, int threads, Problem& p) {
  p.config = LoadConfig(config_path);
  if (threads >= 0) p.config.smc.threads = threads;
  p.data = ProfilesOf(LoadExperimentData(p.config));
  p.distance = MakeDistance(p.config, p.data);
}

RunMetadata Describe(const Problem& p) {
  RunMetadata m;
  m.combabc_version = COMBABC_VERSION;
  m.config_text = p.config.text;
  // Absolute: a resume from another folder must find {config_dir} (and report paths) the same.
  std::error_code ec;
  const fs::path absolute = fs::absolute(p.config.path, ec);
  m.config_path = ec ? p.config.path : absolute.lexically_normal().string();
  m.git_hash = COMBABC_GIT_HASH;
  m.seed = p.config.smc.seed;
  // 0 means all cores (as ThreadPool resolves it): record how many that was.
  m.threads = p.config.smc.threads > 0
                  ? p.config.smc.threads
                  : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  m.estimator = ToString(p.config.smc.estimator);
  const BinarySpace& bits = p.space->binary();
  m.dimension = bits.dimension();
  for (int k = 0; k < bits.dimension(); ++k) m.bit_names.push_back(bits.name(k));
  m.bit_prior_one = bits.bit_prior_one();
  m.distance_components = p.distance->components();
  m.output_positions = p.config.simulator.outputs.coordinates;
  m.position_unit = "m";
  for (std::size_t e = 0; e < p.config.experiments.size(); ++e) {
    const ExperimentConfig& x = p.config.experiments[e];
    const MeasuredProfile& data = p.data[e];
    m.measured.positions.insert(
        m.measured.positions.end(), data.positions.begin(), data.positions.end());
    m.measured.values.insert(m.measured.values.end(), data.values.begin(), data.values.end());
    const JointDistance::Part& part = p.distance->parts()[e];
    m.experiments.push_back({x.name,
                             ExperimentDescription(p.config, x),
                             static_cast<int>(part.distance->output_size()),
                             static_cast<int>(data.positions.size()),
                             static_cast<int>(part.distance->configs().size())});
  }
  m.reals = p.space->reals();
  m.proposal = p.config.smc.proposal;
  m.tempering_form = ToString(p.config.smc.tempering.form);
  m.fingerprint = FingerprintOf(p);
  return m;
}

// `store` is the history on the primary, null on the other workers of a distributed executor.
RunOutcome Execute(Problem& problem,
                   HistoryStore* store,
                   const std::string& history_path,
                   const ResumePoint* resume,
                   bool report,
                   SmcObserver* progress) {
  Executor& executor = *problem.executor;
  PrimaryStore stored(executor, store);
  FanOutObserver observer({&stored, progress});
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
    if (!report) return;
    try {
      outcome.report_directory = WriteReport(store->path(), ReportDirectory(store->path()));
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
  LoadProblem(request.config_path, request.threads, p);
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
  std::optional<HistoryStore> store;
  OnPrimary(*p.executor, [&] {
    store.emplace(HistoryStore::Create(history_path, Describe(p), request.overwrite));
    folders.Keep();
  });
  return Execute(p, store ? &*store : nullptr, history_path, nullptr, request.report, progress);
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
  return Execute(p, store ? &*store : nullptr, history_path, &resume, report, progress);
}

namespace {

// The thresholds an enumeration uses by default: where the config's run would end.
std::vector<double> FinalThresholds(const CalibrationConfig& config) {
  std::vector<double> eps;
  for (std::size_t s = 0; s < config.smc.thresholds.size(); ++s) {
    const ThresholdSchedule& schedule = config.smc.thresholds[s];
    if (schedule.kind == ThresholdKind::kList && !schedule.values.empty()) {
      eps.push_back(schedule.values.back());
    } else if (schedule.kind == ThresholdKind::kQuantile && schedule.target > 0) {
      eps.push_back(schedule.target);
    } else {
      // A quantile schedule without a target (0, its default) adapts down forever: there is no
      // final threshold to enumerate at.
      throw Error(ErrorKind::kUsage,
                  "threshold component " + std::to_string(s + 1) +
                      " has no final threshold in the config (a quantile schedule without "
                      "target); give one per threshold component with --threshold",
                  config.path);
    }
  }
  return eps;
}

std::string Num(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

std::string BitString(const std::vector<std::uint8_t>& bits) {
  std::string s;
  for (std::uint8_t b : bits) s += b ? '1' : '0';
  return s;
}

// RFC 4180 quoting, only when needed.
std::string Field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

void WriteEnumerationFiles(OutputDirectory& dir, const RunMetadata& m, const EnumerationResult& r) {
  const std::size_t d = m.bit_names.size();
  std::ostream& corr = dir.Add("pair_correlations.csv");
  // A bit constant under the posterior has no correlation: written as 0 (docs/algorithm.md).
  corr << "bit";
  for (const std::string& name : m.bit_names) corr << ',' << Field(name);
  corr << '\n';
  for (std::size_t i = 0; i < d && !r.correlations.empty(); ++i) {
    corr << Field(m.bit_names[i]);
    for (std::size_t j = 0; j < d; ++j) corr << ',' << Num(r.correlations[i * d + j]);
    corr << '\n';
  }
  std::ostream& top = dir.Add("top_configurations.csv");
  top << "rank,configuration,bits,prior,posterior";
  for (const DistanceComponent& c : m.distance_components) top << ',' << Field("d_" + c.name);
  top << '\n';
  for (std::size_t k = 0; k < r.top.size(); ++k) {
    const Particle& p = r.top[k];
    top << k + 1 << ',' << p.index << ',' << BitString(p.theta.bits) << ','
        << Num(std::exp(p.log_weight)) << ',' << Num(p.weight);
    for (double x : p.distance) top << ',' << Num(x);
    top << '\n';
  }
  std::ostream& marginals = dir.Add("marginals.csv");
  marginals << "bit,name,prior,posterior\n";
  for (std::size_t k = 0; k < d && !r.marginals.empty(); ++k) {
    marginals << k << ',' << Field(m.bit_names[k]) << ',' << Num(m.bit_prior_one[k]) << ','
              << Num(r.marginals[k]) << '\n';
  }
}

// The enumeration's history, tables and report (after the checks RunEnumeration made).
void WriteEnumeration(const EnumerateRequest& request,
                      const Problem& p,
                      const EnumerationOptions& options,
                      const EnumerationResult& result,
                      EnumerateOutcome& outcome);

// Enumeration visits 2^(free bits) configurations; beyond kMaxEnumerationBits that is refused
// at the config key that sets the bits, before the model is built (Enumerate checks it again for
// library callers, without a file to name).
void CheckEnumerable(const CalibrationConfig& c) {
  const int free = BinarySpace(c.space).num_free();
  if (free <= kMaxEnumerationBits) return;
  const std::string bits = std::to_string(c.space.dimension);
  throw Error(ErrorKind::kConfig,
              "gives " + bits + " bits, " + std::to_string(free) + " free after ties (2^" +
                  std::to_string(free) + " configurations); enumerate takes at most 2^" +
                  std::to_string(kMaxEnumerationBits) +
                  ": tie bits ([sampler] tie, e.g. left/right clamp pairs) to reduce them, or run "
                  "combinatorial ABC-SMC (combabc run)",
              c.path,
              c.bits_line,
              c.bits_key);
}

}  // namespace

EnumerateOutcome RunEnumeration(const EnumerateRequest& request, SmcObserver* progress) {
  OutputFolders folders;  // kept once the enumeration's results are written
  Problem p;
  LoadProblem(request.config_path, request.threads, p);
  CheckEnumerable(p.config);
  MakeExecutor(p, request.executor);
  Executor& executor = *p.executor;

  if (!request.thresholds.empty()) {
    // One per threshold component, in the distance vector's order: name them.
    std::string names;
    std::size_t count = 0;
    for (const DistanceComponent& c : p.distance->components()) {
      if (c.kind != ComponentKind::kThreshold) continue;
      names += (count++ ? ", " : "") + c.name;
    }
    if (request.thresholds.size() != count) {
      throw Error(ErrorKind::kUsage,
                  "gives " + std::to_string(request.thresholds.size()) + " thresholds; give " +
                      std::to_string(count) +
                      ", one per threshold component in this order: " + names,
                  "",
                  0,
                  "--threshold");
    }
  }
  EnumerationOptions options;
  options.thresholds = request.thresholds.empty() ? FinalThresholds(p.config) : request.thresholds;
  options.threads = p.config.smc.threads;
  options.top = request.top;
  options.max_particles = request.max_particles;
  options.keep_outputs = p.config.smc.keep_outputs;
  options.seed = p.config.smc.seed;

  const std::string directory = request.output_directory.empty()
                                    ? ResolvePath(p.config.directory, p.config.output.directory)
                                    : request.output_directory;
  const fs::path history = fs::path(directory) / p.config.output.database;
  const std::string files_directory =
      (history.parent_path() / (history.stem().string() + ".enumeration")).string();
  // Everything that would refuse the results at the end is refused now, before hours of work.
  OnPrimary(executor, [&] {
    std::error_code ec;
    if (!request.overwrite && fs::exists(fs::symlink_status(history, ec))) {
      throw Error(ErrorKind::kCantCreate,
                  "a run history already exists there (use --overwrite to replace it)",
                  history.string());
    }
    if (request.report) CheckReportPossible(ReportDirectory(history.string()));
    folders.Create(directory);
    OutputDirectory::Check(files_directory, request.overwrite);
  });
  BuildModelIn(p, history.string());

  EnumerateOutcome outcome;
  const EnumerationResult result = Enumerate(p.view(), options, progress);
  outcome.configurations = result.configurations;
  outcome.enumerated = result.enumerated;
  outcome.accepted = result.accepted;
  outcome.evidence = result.evidence;
  outcome.wall_seconds = result.wall_seconds;
  outcome.interrupted = result.interrupted;
  if (result.interrupted) return outcome;
  // The files, on the primary only.
  OnPrimary(executor, [&] {
    WriteEnumeration(request, p, options, result, outcome);
    folders.Keep();
  });
  return outcome;
}

namespace {

void WriteEnumeration(const EnumerateRequest& request,
                      const Problem& p,
                      const EnumerationOptions& options,
                      const EnumerationResult& result,
                      EnumerateOutcome& outcome) {
  const std::string directory = request.output_directory.empty()
                                    ? ResolvePath(p.config.directory, p.config.output.directory)
                                    : request.output_directory;
  const fs::path history = fs::path(directory) / p.config.output.database;
  const std::string files_directory =
      (history.parent_path() / (history.stem().string() + ".enumeration")).string();
  RunMetadata metadata = Describe(p);
  // The stored particles carry exact posterior masses, so both marginals are the exact ones; the
  // importance estimator is the one whose weights they are (termination "enumerated" tells).
  metadata.estimator = ToString(Estimator::kImportance);
  auto store = HistoryStore::Create(history.string(), metadata, request.overwrite);
  outcome.history_path = store.path();
  const WaveRecord wave = result.Wave(options.thresholds, p.space->binary().free_prior_one());
  RunSummary summary;
  summary.termination = Termination::kEnumerated;
  summary.message = "exact enumeration of " + std::to_string(result.configurations) +
                    " configurations: " + std::to_string(result.accepted) + " accepted, evidence " +
                    Num(result.evidence);
  summary.waves_completed = 1;
  summary.simulations = result.enumerated;
  summary.wall_seconds = result.wall_seconds;
  try {
    store.OnWaveStart(wave);
    const BatchProgress done{0,
                             result.enumerated,
                             static_cast<std::int64_t>(wave.particles.size()),
                             0,
                             static_cast<int>(wave.particles.size()),
                             result.enumerated,
                             result.wall_seconds,
                             0,
                             {}};
    store.OnBatch(done, wave.particles);
    store.OnWaveEnd(wave);
    store.Finish(summary);
  } catch (const std::exception& e) {
    try {
      store.MarkFailed(e.what());
    } catch (const std::exception&) {
      // The store itself may be what failed (disk full); the first error is the one to report.
    }
    throw;
  }
  OutputDirectory files(files_directory, request.overwrite);
  WriteEnumerationFiles(files, metadata, result);
  files.Commit();
  outcome.enumeration_directory = files_directory;
  if (request.report) {
    try {
      outcome.report_directory = WriteReport(store.path(), ReportDirectory(store.path()));
    } catch (const Error& e) {
      throw Error(e.kind(),
                  "the enumeration is saved in " + store.path() +
                      " ('combabc report' retries the report), but its report failed: " + e.what());
    }
  }
}

}  // namespace

}  // namespace combabc::services
