#pragma once
// [model_choice] (docs/config.md, "Model choice"): the candidate models of an ABC model choice,
// each the config's [model] (or [simulator]) with some keys changed, and its prior probability.
#include <string>
#include <vector>

namespace combabc {

struct CandidateModel {
  std::string name;    // unique, [A-Za-z0-9_.-]+: its history's folder, models/<name>/
  double prior = 0.0;  // P(M_k) before the data; the priors sum to 1
  int line = 0;        // its [[model_choice.model]] header
  // The whole config of this model, as TOML: the file with the model's [model] keys set over the
  // file's and its [simulator] (if it gives one) in place of the file's, without [model_choice].
  // Its run's history records it, so `combabc resume` rebuilds the model from it.
  std::string config_text;
};

struct ModelChoiceConfig {
  std::vector<CandidateModel> models;  // at least two
  // The model the Bayes factors are against (`reference`; default the first).
  std::size_t reference = 0;
  // `method`: "evidence" (default), each model's own run and its evidence; "joint", one run over
  // the model indicator and the models' parameters (docs/algorithm.md, "Model choice").
  bool joint = false;
  int line = 0;  // the [model_choice] table's line
};

// Whether `name` may name a model: 1-64 of [A-Za-z0-9_.-], not "." or "..", since it names the
// model's history folder, models/<name>/ (config_model_choice.cpp).
bool ValidModelName(const std::string& name);
constexpr const char* kModelNameRule =
    "use 1-64 letters, digits, '_', '-' or '.' (it names the model's history folder)";

}  // namespace combabc
