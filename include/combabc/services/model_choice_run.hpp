#pragma once
// `combabc run` and `combabc enumerate` on a config with [model_choice] (docs/config.md, "Model
// choice"; docs/algorithm.md, "Model choice"): each candidate model is calibrated (or enumerated)
// on its own, into models/<name>/ inside the output directory, and the posterior model
// probabilities are computed from the models' evidences and written to model_choice/.
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "combabc/samplers/monte_carlo_error.hpp"
#include "combabc/schedules/threshold_schedule.hpp"
#include "combabc/services/enumerate.hpp"
#include "combabc/services/model_choice.hpp"
#include "combabc/services/run.hpp"

namespace combabc::services {

struct ModelChoiceOutcome {
  bool exact = false;                          // by enumeration
  std::vector<ModelEvidence> evidence;         // per model, in config order
  std::vector<ModelProbability> models;        // per model, in config order
  std::size_t reference = 0;                   // the Bayes factors' reference model
  std::vector<RunOutcome> runs;                // run: per model (empty for enumerate)
  std::vector<EnumerateOutcome> enumerations;  // enumerate: per model
  std::string directory;                       // model_choice/ (summary.json, models.csv)
  bool interrupted = false;                    // a model's run or enumeration was interrupted
  std::string note;  // why model_probabilities.png was not drawn ("" when it was, or not asked)
  // method = "joint": one run (runs[0]) over the models and their parameters. Each model's
  // evidence is then the joint run's evidence times P(M_k | D) / pi_k.
  bool joint = false;
  // joint: the model probabilities after each wave, from that wave's particles (waves.csv).
  std::vector<std::vector<ModelProbability>> by_wave;
  // joint: per model, P(bit = 1 | M_k, D) of each of its bits (bits.csv), and the bits' names.
  std::vector<std::vector<WeightedMoment>> model_bits;
  std::vector<std::vector<std::string>> model_bit_names;
};

// Whether the config file has [model_choice] (reads and checks the whole config).
bool HasModelChoice(const std::string& config_path);

// Runs every model of the config's [model_choice] in turn (method "evidence"; with method "joint"
// one run over all models, its history in <output>/joint/, resumed or read as a model's below),
// each as `combabc run` would run its config, with its history in <output>/models/<name>/. A model
// whose history is there already, from the same model config, is not run again: a finished one is
// read, an unfinished one resumed (so that `combabc run` again continues an interrupted model
// choice); `overwrite` starts every model afresh. `before_model` (may be empty) hears each model's
// name before it runs.
ModelChoiceOutcome RunModelChoice(const RunRequest& request,
                                  SmcObserver* progress = nullptr,
                                  const std::function<void(const std::string&)>& before_model = {});

// The exact model probabilities: every model enumerated (EnumerateRequest's thresholds apply to
// all), into <output>/enumeration/models/<name>/.
ModelChoiceOutcome EnumerateModelChoice(
    const EnumerateRequest& request,
    SmcObserver* progress = nullptr,
    const std::function<void(const std::string&)>& before_model = {});

// One model's run for CombineModelRuns: its name (ValidModelName), prior and history file.
struct ModelRun {
  std::string name;
  double prior = 0.0;
  std::string history_path;
};

// Refuses (Error kUsage, one line) the models of a model choice made outside a config (the Python
// module's Problems): fewer than two, a name that is not ValidModelName or given twice, a prior
// not above 0, or priors that do not sum to 1 (as [model_choice] refuses them).
void CheckModelRuns(std::span<const ModelRun> models);

// Where every model's run must end: each schedule's final threshold (a list's last value, an
// adaptive schedule's target), one per threshold component, since the evidences are comparable
// only at common final thresholds. Error kUsage for a schedule without one (an adaptive schedule
// without target).
std::vector<double> CommonFinalThresholds(std::span<const ThresholdSchedule> schedules);

// Method "evidence" over the models' runs, made: each model's evidence from its history at
// `final_thresholds` (EstimateEvidence, with the distance components its metadata records), the
// probabilities (ModelProbabilities, Bayes factors against models[reference]), and the tables in
// <directory>/model_choice/ (summary.json, models.csv, waves.csv, and with `figure` its figure;
// written by the executor's primary alone, under MPI). RunModelChoice ends with it, and the
// Python module's model choice over Problems calls it once its runs are done. `runs` is left
// empty.
ModelChoiceOutcome CombineModelRuns(std::span<const ModelRun> models,
                                    std::size_t reference,
                                    const std::vector<double>& final_thresholds,
                                    const std::string& directory,
                                    bool overwrite,
                                    bool figure,
                                    const ExecutorFactory& executor = {});

// The model probabilities as the terminal shows them (one line a model, then the Bayes factors'
// reference), ending in a newline.
std::string FormatModelProbabilities(const ModelChoiceOutcome& outcome);

// A joint model choice's bit table of model k: P(bit = 1 | M_k, D) +- se per bit ("" when the
// model has no particle, or for method "evidence", whose models' own answers say it).
std::string FormatJointModelBits(const ModelChoiceOutcome& outcome, std::size_t model);

}  // namespace combabc::services
