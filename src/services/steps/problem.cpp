#include "services/steps/problem.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "services/steps/worker_steps.hpp"
#include "simulators/model_switch.hpp"

#ifndef COMBABC_GIT_HASH
#define COMBABC_GIT_HASH ""
#endif
#ifndef COMBABC_VERSION
#define COMBABC_VERSION "unknown"
#endif

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

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

// A joint model choice: the models' simulators behind a ModelSwitch, over the joint space of the
// model indicator and the models' parameters (simulators/model_switch.hpp). Every model's config
// is the file with its keys set (CandidateModel::config_text); the models' outputs agree (checked
// with the config), so the file's data and metric serve all.
void BuildJointModel(Problem& p, const std::string& history_path) {
  std::vector<std::string> names;
  std::vector<double> prior;
  std::vector<ModelParameters> parameters;
  std::vector<std::unique_ptr<Simulator>> simulators;
  auto folders = std::make_shared<std::vector<std::shared_ptr<const void>>>();
  for (const CandidateModel& model : p.config.model_choice->models) {
    const CalibrationConfig c = ParseConfig(model.config_text, p.config.path);
    names.push_back(model.name);
    prior.push_back(model.prior);
    parameters.push_back({c.space, c.reals, c.joint_priors});
    BuiltSimulator built =
        MakeSimulator(c, WorkDirectoryOf(history_path), p.executor->thread_pool());
    if (p.simulator.handshake.empty()) p.simulator.handshake = built.handshake;
    folders->push_back(std::move(built.folder));
    simulators.push_back(std::move(built.simulator));
  }
  JointSpace joint = [&] {
    try {
      return BuildJointSpace(names, prior, parameters);
    } catch (const Error& e) {
      // Where the models are: BuildJointSpace knows only their names.
      throw Error(
          e.kind(), e.message(), p.config.path, p.config.model_choice->line, "model_choice");
    }
  }();
  p.simulator.simulator = std::make_unique<ModelSwitch>(std::move(simulators), joint.layout);
  p.simulator.folder = std::move(folders);
  p.space.emplace(std::move(joint.space));
}

}  // namespace

void LoadProblem(const std::string& config_path,
                 int threads,
                 Problem& p,
                 const std::string& config_text) {
  p.config = config_text.empty() ? LoadConfig(config_path) : ParseConfig(config_text, config_path);
  // A model choice is run by services/model_choice_run.hpp, whatever its method: by evidence it
  // is several runs, never the file's own [model]; a joint one is one run over the joint space
  // (BuildModel), which that service starts with the config's text, and whose history alone would
  // lack the model-choice tables. A file given directly is refused either way.
  if (p.config.model_choice && (config_text.empty() || !p.config.model_choice->joint)) {
    throw Error(ErrorKind::kUsage,
                "has [model_choice]: run its models with combabc run / enumerate, or "
                "combabc.model_choice from Python",
                config_path);
  }
  if (threads >= 0) p.config.smc.threads = threads;
  p.data = ProfilesOf(LoadExperimentData(p.config));
  p.distance = MakeDistance(p.config, p.data);
}

void MakeExecutor(Problem& p, const ExecutorFactory& factory) {
  p.executor = factory ? factory(p.config.smc.threads)
                       : std::make_unique<ThreadPoolExecutor>(p.config.smc.threads);
}

void BuildModel(Problem& p, const std::string& history_path) {
  // First, as it is cheap: checks the metric's windows and indicators against the simulator's
  // output coordinates and the data before the model is built or anything simulated or stored.
  if (!p.distance) p.distance = MakeDistance(p.config, p.data);
  if (p.config.model_choice && p.config.model_choice->joint) {
    BuildJointModel(p, history_path);
    return;
  }
  p.simulator = MakeSimulator(p.config, WorkDirectoryOf(history_path), p.executor->thread_pool());
  p.low_fidelity =
      MakeLowFidelitySimulator(p.config, WorkDirectoryOf(history_path), p.executor->thread_pool());
  p.space.emplace(BinarySpace(p.config.space), p.config.reals, p.config.joint_priors);
}

void BuildModelIn(Problem& p, const std::string& history_path) {
  OnEvery(*p.executor, [&] { BuildModel(p, history_path); });
}

Fingerprint FingerprintOf(const Problem& p, const CalibrationConfig* config) {
  FingerprintInputs inputs;
  inputs.config = config != nullptr ? config : &p.config;
  inputs.space = &*p.space;
  inputs.data = p.data;
  inputs.components = p.distance->components();
  inputs.version = COMBABC_VERSION;
  inputs.handshake = p.simulator.handshake;
  inputs.low_fidelity_handshake = p.low_fidelity.handshake;
  return ComputeFingerprint(inputs);
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

std::vector<StoredExperiment> ExperimentsOf(const Problem& p) {
  std::vector<StoredExperiment> experiments;
  for (std::size_t e = 0; e < p.config.experiments.size(); ++e) {
    const ExperimentConfig& x = p.config.experiments[e];
    const JointDistance::Part& part = p.distance->parts()[e];
    experiments.push_back({x.name,
                           ExperimentDescription(p.config, x),
                           static_cast<int>(part.distance->output_size()),
                           static_cast<int>(p.data[e].positions.size()),
                           static_cast<int>(part.distance->configs().size())});
  }
  return experiments;
}

std::string CombabcVersion() { return COMBABC_VERSION; }

std::optional<double> FinalThreshold(const ThresholdSchedule& schedule) {
  if (schedule.kind == ThresholdKind::kList) {
    if (schedule.values.empty()) return std::nullopt;
    return schedule.values.back();
  }
  if (schedule.target > 0) return schedule.target;
  return std::nullopt;
}

RunMetadata StampedMetadata() {
  RunMetadata m;
  m.combabc_version = COMBABC_VERSION;
  m.git_hash = COMBABC_GIT_HASH;
  return m;
}

RunMetadata Describe(const Problem& p) {
  RunMetadata m = StampedMetadata();
  m.config_text = p.config.text;
  // Absolute: a resume from another folder must find {config_dir} (and report paths) the same.
  std::error_code ec;
  const fs::path absolute = fs::absolute(p.config.path, ec);
  m.config_path = ec ? p.config.path : absolute.lexically_normal().string();
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
  for (const MeasuredProfile& data : p.data) {
    m.measured.positions.insert(
        m.measured.positions.end(), data.positions.begin(), data.positions.end());
    m.measured.values.insert(m.measured.values.end(), data.values.begin(), data.values.end());
  }
  m.experiments = ExperimentsOf(p);
  m.reals = p.space->reals();
  m.proposal = p.config.smc.proposal;
  m.tempering_form = ToString(p.config.smc.tempering.form);
  m.fingerprint = FingerprintOf(p);
  return m;
}

}  // namespace combabc::services
