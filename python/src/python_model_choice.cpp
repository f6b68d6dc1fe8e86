// combabc._core.model_choice (python_model_choice.hpp).
#include "python_model_choice.hpp"

#include <pybind11/stl.h>

#include <cstddef>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/samplers/smc_options.hpp"
#include "combabc/services/model_choice_run.hpp"

namespace combabc::python {
namespace {

namespace py = pybind11;

// The outcome as plain Python values: per model its probability, error, bound and evidence, and
// its history's path.
py::dict Result(const services::ModelChoiceOutcome& outcome,
                const std::vector<std::string>& histories) {
  py::list models;
  for (std::size_t k = 0; k < outcome.models.size(); ++k) {
    const ModelProbability& p = outcome.models[k];
    const ModelEvidence& e = outcome.evidence[k];
    py::dict model;
    model["name"] = p.name;
    model["prior"] = p.prior;
    model["probability"] = p.probability;
    model["se"] = p.se;
    model["upper_bound_only"] = p.upper_bound_only;
    model["upper"] = p.upper;
    model["log_evidence"] = e.log_evidence;
    model["relative_se"] = e.relative_se;
    model["reached"] = e.reached;
    model["simulations"] = e.simulations;
    model["termination"] = e.termination;
    // A joint model choice is one run: every model's history is it.
    const std::size_t h = outcome.joint ? 0 : k;
    model["history"] = h < histories.size() ? histories[h] : std::string();
    models.append(model);
  }
  py::dict result;
  result["exact"] = outcome.exact;
  result["reference"] =
      outcome.models.empty() ? std::string() : outcome.models[outcome.reference].name;
  result["models"] = models;
  result["directory"] = outcome.directory;
  result["note"] = outcome.note;  // why the figure per wave was not drawn ("" if it was)
  return result;
}

// A config's [model_choice], run or enumerated.
py::dict ModelChoice(const std::string& config_path,
                     int threads,
                     const std::string& output_directory,
                     bool overwrite,
                     bool report,
                     bool exact) {
  services::ModelChoiceOutcome outcome;
  std::vector<std::string> histories;
  {
    const py::gil_scoped_release release;
    if (exact) {
      services::EnumerateRequest request;
      request.config_path = config_path;
      request.threads = threads;
      request.output_directory = output_directory;
      request.overwrite = overwrite;
      request.report = report;
      outcome = services::EnumerateModelChoice(request);
      for (const auto& e : outcome.enumerations) histories.push_back(e.history_path);
    } else {
      services::RunRequest request;
      request.config_path = config_path;
      request.threads = threads;
      request.output_directory = output_directory;
      request.overwrite = overwrite;
      request.report = report;
      outcome = services::RunModelChoice(request);
      for (const auto& r : outcome.runs) histories.push_back(r.history_path);
    }
  }
  return Result(outcome, histories);
}

std::vector<services::ModelRun> Runs(const std::vector<std::string>& names,
                                     const std::vector<double>& priors,
                                     const std::vector<std::string>& histories) {
  if (priors.size() != names.size() || histories.size() != names.size()) {
    throw Error(ErrorKind::kUsage, "model choice: one prior and one history per model");
  }
  std::vector<services::ModelRun> runs;
  for (std::size_t k = 0; k < names.size(); ++k) {
    runs.push_back({names[k], priors[k], histories[k]});
  }
  return runs;
}

// The Problems' model choice (combabc.model_choice over Problems), once each model has run: the
// same tables as a config's, by the same service.
py::dict CombineRuns(const std::vector<std::string>& names,
                     const std::vector<double>& priors,
                     const std::vector<std::string>& histories,
                     const std::vector<double>& final_thresholds,
                     const std::string& directory,
                     bool overwrite,
                     bool report) {
  const std::vector<services::ModelRun> runs = Runs(names, priors, histories);
  services::ModelChoiceOutcome outcome;
  {
    const py::gil_scoped_release release;
    outcome = services::CombineModelRuns(runs, 0, final_thresholds, directory, overwrite, report);
  }
  return Result(outcome, histories);
}

}  // namespace

void RegisterModelChoice(py::module_& m) {
  m.def("model_choice",
        &ModelChoice,
        "Runs (or with exact=True enumerates) every model of the config's [model_choice]; returns "
        "the model probabilities (docs/config.md, \"Model choice\")",
        py::arg("config_path"),
        py::arg("threads") = -1,
        py::arg("output_directory") = std::string(),
        py::arg("overwrite") = false,
        py::arg("report") = false,
        py::arg("exact") = false);
  m.def(
      "check_model_runs",
      [](const std::vector<std::string>& names, const std::vector<double>& priors) {
        services::CheckModelRuns(Runs(names, priors, std::vector<std::string>(names.size())));
      },
      "Refuses a model choice's names and priors as [model_choice] does (combabc.Error)",
      py::arg("names"),
      py::arg("priors"));
  m.def(
      "common_final_thresholds",
      [](const SmcOptions& options) { return services::CommonFinalThresholds(options.thresholds); },
      "The options' final thresholds, one per threshold component, where a model choice compares "
      "the models' evidences (combabc.Error for a schedule without one)",
      py::arg("options"));
  m.def("combine_model_runs",
        &CombineRuns,
        "The model probabilities from the models' finished runs (method \"evidence\"), written "
        "to <directory>/model_choice/ as a config's model choice writes them",
        py::arg("names"),
        py::arg("priors"),
        py::arg("histories"),
        py::arg("final_thresholds"),
        py::arg("directory"),
        py::arg("overwrite") = false,
        py::arg("report") = false);
}

}  // namespace combabc::python
