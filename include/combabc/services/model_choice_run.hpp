#pragma once
// `combabc run` and `combabc enumerate` on a config with [model_choice] (docs/config.md, "Model
// choice"; docs/algorithm.md, "Model choice"): each candidate model is calibrated (or enumerated)
// on its own, into models/<name>/ inside the output directory, and the posterior model
// probabilities are computed from the models' evidences and written to model_choice/.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "combabc/samplers/monte_carlo_error.hpp"
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

// The model probabilities as the terminal shows them (one line a model, then the Bayes factors'
// reference), ending in a newline.
std::string FormatModelProbabilities(const ModelChoiceOutcome& outcome);

// A joint model choice's bit table of model k: P(bit = 1 | M_k, D) +- se per bit ("" when the
// model has no particle, or for method "evidence", whose models' own answers say it).
std::string FormatJointModelBits(const ModelChoiceOutcome& outcome, std::size_t model);

}  // namespace combabc::services
