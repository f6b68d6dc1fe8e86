// combabc._core's runs of problems whose simulator (and optionally distance) is written in Python
// (combabc.run(problem, options), combabc.resume(path, problem, options)): the Python functions
// wrapped as the engine's Simulator and Distance, then services::RunProblem, the steps a config's
// run and resume take.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "answer_binding.hpp"
#include "bindings.hpp"
#include "combabc/distances/euclidean_distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/services/run.hpp"
#include "python_call.hpp"
#include "python_distance.hpp"
#include "python_prior.hpp"
#include "python_simulator.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

// A problem whose simulator (and optionally distance) is written in Python: combabc.Problem's
// fields and the options of combabc.run(problem, options) (python/combabc/__init__.py).
struct SmcRequest {
  BinarySpace space;
  std::vector<ContinuousParameter> reals;
  // Joint priors: the names of the reals each covers (declared with kind "joint") and the prior.
  std::vector<std::pair<std::vector<std::string>, PythonJointPrior>> priors;
  py::object simulator;  // f(bits[, reals]) (PythonSimulator)
  bool batch = false;    // f takes a batch
  bool rng = false;      // f takes rng=
  std::vector<double> observed;
  SmcOptions options;
  // None: EuclideanDistance to `observed`; or a Python callable (PythonDistance) whose k values
  // are named by `components` (empty: one value named "distance").
  py::object distance;
  bool distance_batch = false;
  std::vector<std::string> components;
  // None, or a multi-fidelity run's cheap simulator (SmcProblem::low_fidelity): called like
  // `simulator` (the same batch and rng), m outputs standing for its m.
  py::object low_fidelity;
  // The outputs' coordinates (Problem(positions=...)) and their unit; empty: by index.
  std::vector<double> positions;
  std::string position_unit;
};

// Where a Python run writes: nothing (empty path), a new history (combabc.run with
// output_directory, optionally from a finished run's posterior) or the continuation of one
// (combabc.resume with the problem, with its raised limits).
struct PythonRunFile {
  std::string history_path;
  bool overwrite = false;
  bool resume = false;
  bool report = false;
  std::string start_from;
  services::StopLimits limits;
};

// Raises the user's Python exception that ended a run as itself (its type, message and
// traceback), with the engine's line (wave and candidate) attached as a note; else rethrows. A
// KeyboardInterrupt (Ctrl-C that reached Python inside the simulator or distance) is an interrupt
// like one seen between batches: it gets `interrupted`, the note that says how to continue.
void RaiseFirstError(const FirstPythonError& first_error,
                     const std::exception& e,
                     const std::string& interrupted = "") {
  std::optional<py::error_already_set> raised = first_error.error();
  if (!raised) return;  // the caller rethrows the engine's error
  const bool interrupt = raised->matches(PyExc_KeyboardInterrupt);
  const std::string note =
      interrupt && !interrupted.empty() ? interrupted : std::string("combabc: ") + e.what();
  if (py::hasattr(raised->value(), "add_note")) raised->value().attr("add_note")(note);
  throw *raised;
}

// The engine's objects around the request's Python functions, made (GIL held) before the run.
class PythonParts {
 public:
  PythonParts(const SmcRequest& request, py::object simulation_failed)
      : space_(MakeSpace(request)), options_(request.options) {
    if (request.observed.empty()) {
      throw Error(ErrorKind::kConfig, "the observed data are empty", {}, 0, "observed");
    }
    if (request.distance.is_none()) {
      if (!request.components.empty()) {
        throw Error(ErrorKind::kConfig,
                    "components name the values of a distance written in Python; the built-in "
                    "Euclidean distance has one, \"euclidean\"",
                    {},
                    0,
                    "components");
      }
      distance_ = std::make_unique<EuclideanDistance>(request.observed);
    } else {
      distance_ = std::make_unique<PythonDistance>(request.distance,
                                                   request.distance_batch,
                                                   request.components,
                                                   request.observed,
                                                   simulation_failed,
                                                   first_error_);
    }
    // The default kernel resolved for this space, as the history records it (kind = "auto").
    options_.proposal = ResolvedProposal(
        options_.proposal,
        AnyUncertainBit(space_.binary().free_prior_one()) && space_.num_reals() > 0);
    for (const auto& [names, prior] : request.priors) {
      if (prior.error()) prior.error()->Clear();  // what its check or an earlier run raised
    }
    // The cheap simulator is called as the simulator is (the same batch and rng).
    auto wrap = [&](std::optional<PythonSimulator>& made, const py::object& function) {
      made.emplace(function,
                   request.batch,
                   static_cast<int>(request.observed.size()),
                   space_.num_reals(),
                   simulation_failed,
                   request.rng,
                   first_error_);
    };
    wrap(simulator_, request.simulator);
    if (options_.method == SamplerMethod::kResampleMove) CheckMoves(options_.moves);
    if (request.low_fidelity.is_none()) return;
    CheckMultiFidelity(options_.multi_fidelity);
    // As a config's [simulator.low_fidelity] with method = "resample_move".
    if (options_.method == SamplerMethod::kResampleMove) {
      throw py::value_error(
          "SmcOptions: method = \"resample_move\": moves do not apply to multi-fidelity runs "
          "(Problem(low_fidelity=...)); use method = \"rejection\"");
    }
    wrap(cheap_, request.low_fidelity);
  }

  // What RunProblem runs: the space's reals (a joint real's mean and sd are its prior's, which
  // the fingerprint then holds: a custom prior's functions cannot be fingerprinted, the moments
  // of their draws can), and how the functions are called in place of their code.
  services::ProblemRunRequest Request(const SmcRequest& request) const {
    services::ProblemRunRequest run;
    run.problem.space = &space_;
    run.problem.simulator = &*simulator_;
    run.problem.distance = distance_.get();
    run.problem.low_fidelity = cheap_ ? &*cheap_ : nullptr;
    run.options = options_;
    run.observed = request.observed;
    run.positions = request.positions;
    run.position_unit = request.position_unit;
    auto flag = [](bool value) { return std::string(value ? "1" : "0"); };
    run.calling = {{"batch", flag(request.batch)},
                   {"rng", flag(request.rng)},
                   {"python_distance", flag(!request.distance.is_none())},
                   {"distance_batch", flag(request.distance_batch)}};
    return run;
  }

  const FirstPythonError& first_error() const { return first_error_; }

 private:
  // Checks the joint priors (CheckJointPrior) before any simulation.
  static ParameterSpace MakeSpace(const SmcRequest& request) {
    std::vector<JointPriorGroup> joint;
    joint.reserve(request.priors.size());
    for (const auto& [names, prior] : request.priors) joint.push_back({names, prior.prior()});
    return ParameterSpace(request.space, request.reals, std::move(joint));
  }

  FirstPythonError first_error_;  // outlives the simulator and distance that keep it
  ParameterSpace space_;
  SmcOptions options_;
  std::unique_ptr<Distance> distance_;
  std::optional<PythonSimulator> simulator_;
  std::optional<PythonSimulator> cheap_;
};

py::dict RunSmc(const SmcRequest& request, const PythonRunFile& file) {
  const PythonParts parts(request, py::module_::import("combabc._core").attr("SimulationFailed"));
  services::ProblemRunRequest run = parts.Request(request);
  run.history_path = file.history_path;
  run.overwrite = file.overwrite;
  run.resume = file.resume;
  run.report = file.report;
  run.start_from = file.start_from;
  run.limits = file.limits;
  const std::string interrupted = file.history_path.empty()
                                      ? "combabc: run interrupted"
                                      : ContinueNote(file.history_path, ", problem, options");
  const auto outcome = RunReleased<services::RunOutcome>(
      [&](SmcObserver* signals) { return services::RunProblem(run, signals); },
      [&](const services::RunOutcome&) { return std::string(interrupted); },
      [&](const std::exception& e) {
        // A custom prior's own exception, else the simulator's or distance's, as itself.
        for (const auto& [names, prior] : request.priors) {
          if (prior.error() && prior.error()->error()) RaiseFirstError(*prior.error(), e);
        }
        RaiseFirstError(parts.first_error(), e, interrupted);
      });
  if (!file.history_path.empty()) {
    // Read back from the file, as a config run's, so that the arrays are what export writes.
    return LoadHistory(file.history_path, outcome.report_directory);
  }
  // Named as a history file of the same run would be.
  const RunMetadata metadata = services::DescribeProblem(run);
  py::dict result = HistoryToDict(outcome.history, NamesOf(metadata, outcome.history));
  result["seed"] = run.options.seed;
  result["bit_prior_one"] = metadata.bit_prior_one;
  result["real_priors"] = RealPriors(metadata.reals);
  // The answer the run handed over (History.answer() reads it, as it would read the file's).
  if (outcome.answer) result["answer"] = AnswerToDict(*outcome.answer);
  return result;
}

}  // namespace

void BindProblemRuns(py::module_& m) {
  py::class_<SmcRequest>(m, "SmcRequest")
      .def(py::init([](const BinarySpace& space,
                       std::vector<ContinuousParameter> reals,
                       std::vector<std::pair<std::vector<std::string>, PythonJointPrior>> priors,
                       py::object simulator,
                       bool batch,
                       bool rng,
                       std::vector<double> observed,
                       const SmcOptions& options,
                       py::object distance,
                       bool distance_batch,
                       std::vector<std::string> components,
                       py::object low_fidelity,
                       std::vector<double> positions,
                       std::string position_unit) {
             return SmcRequest{.space = space,
                               .reals = std::move(reals),
                               .priors = std::move(priors),
                               .simulator = std::move(simulator),
                               .batch = batch,
                               .rng = rng,
                               .observed = std::move(observed),
                               .options = options,
                               .distance = std::move(distance),
                               .distance_batch = distance_batch,
                               .components = std::move(components),
                               .low_fidelity = std::move(low_fidelity),
                               .positions = std::move(positions),
                               .position_unit = std::move(position_unit)};
           }),
           py::kw_only(),
           py::arg("space"),
           py::arg("reals") = std::vector<ContinuousParameter>{},
           py::arg("priors") = std::vector<std::pair<std::vector<std::string>, PythonJointPrior>>{},
           py::arg("simulator"),
           py::arg("batch") = false,
           py::arg("rng") = false,
           py::arg("observed"),
           py::arg("options"),
           py::arg("distance") = py::none(),
           py::arg("distance_batch") = false,
           py::arg("components") = std::vector<std::string>{},
           py::arg("low_fidelity") = py::none(),
           py::arg("positions") = std::vector<double>{},
           py::arg("position_unit") = std::string());
  m.def(
      "run_smc",
      [](const SmcRequest& request,
         const std::string& history_path,
         bool overwrite,
         bool resume,
         bool report,
         const std::string& start_from,
         std::optional<std::int64_t> max_simulations,
         std::optional<double> max_wall_time,
         std::optional<double> min_acceptance_rate,
         std::optional<double> max_failure_fraction,
         std::optional<int> waves) {
        return RunSmc(request,
                      {.history_path = history_path,
                       .overwrite = overwrite,
                       .resume = resume,
                       .report = report,
                       .start_from = start_from,
                       .limits = {max_simulations,
                                  max_wall_time,
                                  min_acceptance_rate,
                                  max_failure_fraction,
                                  waves}});
      },
      py::arg("request"),
      py::arg("history_path") = std::string(),
      py::arg("overwrite") = false,
      py::arg("resume") = false,
      py::arg("report") = false,
      py::arg("start_from") = std::string(),
      py::arg("max_simulations") = py::none(),
      py::arg("max_wall_time") = py::none(),
      py::arg("min_acceptance_rate") = py::none(),
      py::arg("max_failure_fraction") = py::none(),
      py::arg("waves") = py::none());
}

}  // namespace combabc::python
