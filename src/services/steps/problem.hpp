#pragma once
// What a run, a resume and an enumeration sample: the config, the measured data, the metric, the
// parameter space, the executor and the simulator, built the same way for each. Private to
// src/services.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/config/distance_from_config.hpp"
#include "combabc/core/executor.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/metrics/joint_distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/services/executor_factory.hpp"
#include "services/adapters/simulator_factory.hpp"
#include "services/steps/run_fingerprint.hpp"

namespace combabc::services {

// Everything a run needs besides its history: built identically for a new run and a resume,
// which is what makes a resumed history equal to an uninterrupted one.
struct Problem {
  CalibrationConfig config;
  std::vector<MeasuredProfile> data;  // one per experiment, as the metric compares them
  std::unique_ptr<JointDistance> distance;
  std::optional<ParameterSpace> space;
  std::unique_ptr<Executor> executor;
  // Last: external processes end before anything else goes.
  // A run that adds experiments to a finished one: its posterior, where wave 0 starts.
  std::optional<StartPopulation> start;
  BuiltSimulator low_fidelity;  // a multi-fidelity run's cheap simulator, else none
  BuiltSimulator simulator;

  SmcProblem view() const {
    SmcProblem v{&*space, simulator.simulator.get(), distance.get()};
    v.executor = executor.get();
    v.low_fidelity = low_fidelity.simulator.get();
    v.start = start ? &*start : nullptr;
    return v;
  }
};

// A new run's problem from its config file: the config (threads >= 0 overrides the config's), the
// measured data read from disk and the metric; BuildModelIn follows once the output folder
// exists. (A resume takes the data stored in its history.) `config_text`, when not empty, is read
// in place of the file (a model choice's candidate model).
void LoadProblem(const std::string& config_path,
                 int threads,
                 Problem& p,
                 const std::string& config_text = {});

// The executor for the problem's threads (after LoadProblem or the resume's config).
void MakeExecutor(Problem& p, const ExecutorFactory& factory);

// history_path: the run's history file; an external simulator works in a folder beside it.
void BuildModel(Problem& p, const std::string& history_path);

// Builds the model on every worker once the output folder exists (an external simulator works
// inside it).
void BuildModelIn(Problem& p, const std::string& history_path);

// `config` defaults to the problem's own; resume also asks what another reading of it would give.
Fingerprint FingerprintOf(const Problem& p, const CalibrationConfig* config = nullptr);

// The experiments as the history's experiment table records them (name, description, and how
// many outputs, measured points and components each has).
std::vector<StoredExperiment> ExperimentsOf(const Problem& p);

// The measured profiles a history recorded, one per experiment (`path` names it in errors).
std::vector<MeasuredProfile> StoredProfiles(const RunMetadata& m, const std::string& path);

// The run's metadata as its history stores it (the fingerprint included).
RunMetadata Describe(const Problem& p);

// This combabc's version, as histories and fingerprints record it.
std::string CombabcVersion();

// Where a threshold schedule ends: a list's last value, an adaptive schedule's target; none for an
// adaptive schedule without a target (0, its default), which adapts down forever. Enumeration and
// model choice both compare at these.
std::optional<double> FinalThreshold(const ThresholdSchedule& schedule);

// A new history's metadata, stamped with this combabc's version and git hash.
RunMetadata StampedMetadata();

}  // namespace combabc::services
