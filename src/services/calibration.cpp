#include "combabc/services/calibration.hpp"

#include <algorithm>
#include <filesystem>
#include <optional>
#include <thread>

#include "combabc/config/distance_from_config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/metrics/composite_distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/services/sensor_simulator.hpp"
#include "services/fan_out_observer.hpp"
#include "services/report_checks.hpp"
#include "services/run_fingerprint.hpp"

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
  std::vector<double> data_positions;  // metres
  std::vector<double> data_values;
  std::unique_ptr<SensorSimulator> simulator;
  std::unique_ptr<CompositeDistance> distance;
  std::optional<ParameterSpace> space;

  SmcProblem view() const { return {&*space, simulator.get(), distance.get()}; }
};

void BuildModel(Problem& p) {
  // First, as it is cheap: checks the metric's windows and indicators against the model's output
  // positions and the data before the model is assembled or anything simulated or stored.
  p.distance = MakeDistance(p.config, p.data_positions, p.data_values);
  p.simulator = std::make_unique<SensorSimulator>(p.config.model);
  const int clamps = p.simulator->model().num_clamps();
  if (p.config.space.dimension != clamps) {
    throw Error(ErrorKind::kConfig,
                "the sampler has " + std::to_string(p.config.space.dimension) +
                    " bits; the model has " + std::to_string(clamps) + " clamps",
                p.config.path,
                0,
                "model");
  }
  p.space.emplace(BinarySpace(p.config.space));
}

Fingerprint FingerprintOf(const Problem& p) {
  FingerprintInputs inputs;
  inputs.config = &p.config;
  inputs.space = &*p.space;
  inputs.data_positions = p.data_positions;
  inputs.data_values = p.data_values;
  inputs.components = p.distance->components();
  inputs.version = COMBABC_VERSION;
  return ComputeFingerprint(inputs);
}

RunMetadata Describe(const Problem& p) {
  RunMetadata m;
  m.combabc_version = COMBABC_VERSION;
  m.config_text = p.config.text;
  m.config_path = p.config.path;
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
  m.output_positions = p.simulator->model().output_positions();
  m.position_unit = "m";
  m.measured.positions = p.data_positions;
  m.measured.values = p.data_values;
  m.reals = p.space->reals();
  m.proposal = p.config.smc.proposal;
  m.tempering_form = ToString(p.config.smc.tempering.form);
  m.fingerprint = FingerprintOf(p);
  return m;
}

RunOutcome Execute(Problem& problem,
                   HistoryStore& store,
                   const ResumePoint* resume,
                   bool report,
                   SmcObserver* progress) {
  FanOutObserver observer({&store, progress});
  RunOutcome outcome;
  outcome.history_path = store.path();
  try {
    outcome.history = RunCombinatorialSmc(problem.view(), problem.config.smc, &observer, resume);
  } catch (const std::exception& e) {
    try {
      store.MarkFailed(e.what());
    } catch (const std::exception&) {
      // The store itself may be what failed (disk full); the first error is the one to report.
    }
    throw;
  }
  store.Finish(outcome.history.summary);
  if (report) {
    try {
      outcome.report_directory = WriteReport(store.path(), ReportDirectory(store.path()));
    } catch (const Error& e) {
      // One line still, but saying that the run itself is safe and how to retry the report.
      throw Error(e.kind(),
                  "the run is saved in " + store.path() +
                      " ('combabc report' retries the report), " +
                      "but its report failed: " + e.what());
    }
  }
  return outcome;
}

}  // namespace

RunOutcome RunCalibration(const RunRequest& request, SmcObserver* progress) {
  Problem p;
  p.config = LoadConfig(request.config_path);
  if (request.threads >= 0) p.config.smc.threads = request.threads;
  const auto data = LoadMeasuredData(p.config.data, p.config.directory);
  p.data_positions = data.positions;
  p.data_values = data.displacements;
  BuildModel(p);

  std::string directory = request.output_directory.empty()
                              ? ResolvePath(p.config.directory, p.config.output.directory)
                              : request.output_directory;
  const std::string history_path = (fs::path(directory) / p.config.output.database).string();
  if (request.report) CheckReportPossible(ReportDirectory(history_path));
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) {
    throw Error(
        ErrorKind::kCantCreate, "cannot create output directory: " + ec.message(), directory);
  }
  auto store = HistoryStore::Create(history_path, Describe(p), request.overwrite);
  return Execute(p, store, nullptr, request.report, progress);
}

RunOutcome ResumeCalibration(const std::string& history_path,
                             int threads,
                             bool report,
                             SmcObserver* progress) {
  auto store = HistoryStore::Open(history_path);
  const auto metadata = store.LoadMetadata();
  if (metadata.status == RunStatus::kFinished) {
    throw Error(ErrorKind::kUsage,
                "the run has already finished (" + metadata.termination +
                    "); nothing to resume. Use 'combabc report' or 'combabc export'",
                history_path);
  }
  Problem p;
  p.config = ParseConfig(metadata.config_text, metadata.config_path);
  if (threads >= 0) p.config.smc.threads = threads;
  // The measured data as the run first used them, not as the CSV reads today.
  p.data_positions = metadata.measured.positions;
  p.data_values = metadata.measured.values;
  BuildModel(p);
  // The rebuilt problem must be the one the run started with, or the continuation would not
  // equal an uninterrupted run. Checked before BeginResume rewrites anything.
  CheckResumeFingerprint(metadata.fingerprint,
                         FingerprintOf(p),
                         history_path,
                         p.config.data.csv,
                         metadata.combabc_version,
                         COMBABC_VERSION);
  if (report) CheckReportPossible(ReportDirectory(history_path));
  const auto resume = store.BeginResume();
  return Execute(p, store, &resume, report, progress);
}

}  // namespace combabc::services
