#pragma once
// `combabc run` and `combabc enumerate` on a config with [model_choice] (docs/config.md, "Model
// choice"; docs/algorithm.md, "Model choice"): each candidate model is calibrated (or enumerated)
// on its own, into models/<name>/ inside the output directory, and the posterior model
// probabilities are computed from the models' evidences and written to model_choice/.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

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
};

// Whether the config file has [model_choice] (reads and checks the whole config).
bool HasModelChoice(const std::string& config_path);

// Runs every model of the config's [model_choice] in turn, each as `combabc run` would run its
// config, with its history in <output>/models/<name>/. A model whose history is there already,
// from the same model config, is not run again: a finished one is read, an unfinished one resumed
// (so that `combabc run` again continues an interrupted model choice); `overwrite` starts every
// model afresh. `before_model` (may be empty) hears each model's name before it runs.
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

}  // namespace combabc::services
