// combabc._core: the compiled half of the Python module (docs/python.md). It binds the options and
// parameter types, runs config files through the same services as the CLI, runs problems whose
// simulator is written in Python, and reads histories as NumPy arrays. The pure-Python package
// (python/combabc/) wraps it in DataFrames. The GIL is released while C++ works.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "batch_random.hpp"
#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/distances/euclidean_distance.hpp"
#include "combabc/export/export.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/services/enumerate.hpp"
#include "combabc/services/history_tools.hpp"
#include "combabc/services/report.hpp"
#include "combabc/services/run.hpp"
#include "combabc/services/simulate.hpp"
#include "history_arrays.hpp"
#include "python_call.hpp"
#include "python_distance.hpp"
#include "python_history.hpp"
#include "python_model_choice.hpp"
#include "python_prior.hpp"
#include "python_simulator.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

template <NamedEnum E>
E Parse(const std::string& text, const std::string& field) {
  const std::optional<E> value = ParseEnum<E>(text);
  if (!value) {
    throw Error(ErrorKind::kConfig,
                "unknown value " + Excerpt(text) + "; expected one of " + EnumChoices<E>(),
                {},
                0,
                field);
  }
  return *value;
}

// Ctrl-C from Python: polled between batches on the thread that called the run (the Python thread
// that started it, where Python runs its signal handlers), it runs them and stops the run when one
// raised (KeyboardInterrupt). The run ends as interrupted (a config run stays resumable) and the
// caller raises the error again.
class PythonSignals final : public SmcObserver {
 public:
  bool ShouldStop() override {
    if (raised_) return true;
    const py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) raised_.emplace();  // takes the pending exception
    return raised_.has_value();
  }
  // Raises the exception a signal handler raised, if any (GIL held), with `note` attached.
  void RaiseIfInterrupted(const std::string& note) {
    if (!raised_) return;
    if (!note.empty() && py::hasattr(raised_->value(), "add_note")) {
      raised_->value().attr("add_note")(note);
    }
    throw *raised_;
  }

 private:
  std::optional<py::error_already_set> raised_;
};

HistoryNames NamesOf(const RunMetadata& metadata, const RunHistory& history) {
  HistoryNames names;
  for (int k = 0; k < metadata.dimension; ++k) {
    names.bits.push_back(BitName(metadata, static_cast<std::size_t>(k)));
  }
  for (const ContinuousParameter& p : metadata.reals) names.reals.push_back(p.name);
  for (const DistanceComponent& c : metadata.distance_components) {
    names.components.push_back(c.name);
  }
  names.estimator = metadata.estimator;
  names.binary_kernel = ToString(metadata.proposal.binary);
  names.continuous_kernel = ToString(metadata.proposal.continuous);
  names.exact = metadata.termination == ToString(Termination::kEnumerated);
  names.bit_prior_one = metadata.bit_prior_one;
  std::size_t thresholds = 0;
  for (const DistanceComponent& c : metadata.distance_components) {
    if (c.kind != ComponentKind::kIndicator) ++thresholds;
  }
  if (!history.waves.empty()) thresholds = history.waves.front().thresholds.size();
  names.threshold_columns = ThresholdColumns(metadata, thresholds);
  names.distance_columns = DistanceColumns(metadata, metadata.distance_components.size());
  return names;
}

// The arguments a prior kind takes, as the config's [parameters.<name>] table (docs/config.md).
bool UsesBounds(PriorKind kind) {
  return kind == PriorKind::kUniform || kind == PriorKind::kTruncatedNormal ||
         kind == PriorKind::kJoint;
}
// A joint real's mean and sd are its joint prior's (set by ParameterSpace).
bool UsesNormal(PriorKind kind) { return kind != PriorKind::kUniform && kind != PriorKind::kJoint; }

// ContinuousParameter(name, kind, low, high, mean, sd): an argument the kind does not use is
// refused rather than ignored, one it uses and was not given keeps ContinuousPrior's default, and
// the prior is checked here, so a bad one fails at construction, naming the parameter, not when
// the run starts.
ContinuousParameter MakeContinuousParameter(std::string name,
                                            const std::string& kind,
                                            std::optional<double> low,
                                            std::optional<double> high,
                                            std::optional<double> mean,
                                            std::optional<double> sd) {
  const std::string where = "ContinuousParameter(" + Excerpt(name) + ")";
  ContinuousParameter p;
  p.name = std::move(name);
  p.prior.kind = Parse<PriorKind>(kind, where + ".kind");
  if (p.prior.kind == PriorKind::kJoint) {  // unbounded unless low or high say otherwise
    p.prior.low = -HUGE_VAL;
    p.prior.high = HUGE_VAL;
  }
  const std::string kind_text(ToString(p.prior.kind));
  auto take = [&](const char* key, const std::optional<double>& value, bool used, double& field) {
    if (!value) return;
    if (!used) {
      throw Error(ErrorKind::kConfig,
                  "not used by kind = \"" + kind_text + "\" (it takes " +
                      (UsesBounds(p.prior.kind) ? "low and high" : "mean and sd") + ")",
                  {},
                  0,
                  where + "." + key);
    }
    field = *value;
  };
  take("low", low, UsesBounds(p.prior.kind), p.prior.low);
  take("high", high, UsesBounds(p.prior.kind), p.prior.high);
  take("mean", mean, UsesNormal(p.prior.kind), p.prior.mean);
  take("sd", sd, UsesNormal(p.prior.kind), p.prior.sd);
  std::string why;
  if (!p.prior.IsValid(&why)) throw Error(ErrorKind::kConfig, why, {}, 0, where);
  return p;
}

// ThresholdSchedule(kind, values, quantile, initial, target, *, weighted, acceptance_rate,
// ess_fraction): a keyword that only another kind uses is refused rather than ignored.
ThresholdSchedule MakeThresholdSchedule(const std::string& kind,
                                        std::vector<double> values,
                                        double quantile,
                                        double initial,
                                        double target,
                                        std::optional<bool> weighted,
                                        std::optional<double> acceptance_rate,
                                        std::optional<double> ess_fraction) {
  ThresholdSchedule s;
  s.kind = Parse<ThresholdKind>(kind, "kind");
  s.values = std::move(values);
  s.quantile = quantile;
  s.initial = initial;
  s.target = target;
  auto only = [&](const char* key, bool given, ThresholdKind user) {
    if (given && s.kind != user) {
      throw py::value_error(std::string("ThresholdSchedule: ") + key +
                            " is only used by kind = \"" + ToString(user) + "\", not \"" +
                            ToString(s.kind) + "\"");
    }
  };
  only("weighted", weighted.has_value(), ThresholdKind::kQuantile);
  only("acceptance_rate", acceptance_rate.has_value(), ThresholdKind::kAcceptance);
  only("ess_fraction", ess_fraction.has_value(), ThresholdKind::kEss);
  s.weighted = weighted.value_or(s.weighted);
  s.acceptance_rate = acceptance_rate.value_or(s.acceptance_rate);
  s.ess_fraction = ess_fraction.value_or(s.ess_fraction);
  return s;
}

// ContinuousParameter('k', kind='uniform', low=0.5, high=2.0): the arguments its kind uses.
std::string ContinuousParameterRepr(const ContinuousParameter& p) {
  auto arg = [](const char* key, double value) {
    return std::string(", ") + key + "=" + py::repr(py::float_(value)).cast<std::string>();
  };
  std::string text = "ContinuousParameter(" + py::repr(py::str(p.name)).cast<std::string>() +
                     ", kind='" + std::string(ToString(p.prior.kind)) + "'";
  if (UsesBounds(p.prior.kind)) text += arg("low", p.prior.low) + arg("high", p.prior.high);
  if (UsesNormal(p.prior.kind)) text += arg("mean", p.prior.mean) + arg("sd", p.prior.sd);
  return text + ")";
}

// Each continuous parameter's prior as summary.json's "reals" give it (History.real_priors).
py::list RealPriors(const std::vector<ContinuousParameter>& reals) {
  py::list priors;
  for (const ContinuousParameter& r : reals) {
    py::dict prior;
    prior["kind"] = std::string(ToString(r.prior.kind));
    prior["low"] = r.prior.low;
    prior["high"] = r.prior.high;
    prior["mean"] = r.prior.mean;
    prior["sd"] = r.prior.sd;
    priors.append(prior);
  }
  return priors;
}

py::dict LoadHistory(const std::string& path) {
  RunMetadata metadata;
  RunHistory history;
  {
    const py::gil_scoped_release release;
    const HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
    metadata = store.LoadMetadata();
    history = store.LoadHistory();
  }
  py::dict result = HistoryToDict(history, NamesOf(metadata, history));
  result["status"] = std::string(ToString(metadata.status));
  // The file's termination, empty until the run ended by a criterion (a failed or killed run):
  // the loaded summary's enum cannot say "none" and would read max_waves.
  result["summary"].cast<py::dict>()["termination"] = metadata.termination;
  result["bit_prior_one"] = metadata.bit_prior_one;
  result["real_priors"] = RealPriors(metadata.reals);
  result["seed"] = metadata.seed;
  result["path"] = path;
  // What the NetCDF export records beside the particles (History.to_inference_data).
  result["measured_position"] = metadata.measured.positions;
  result["measured_value"] = metadata.measured.values;
  result["position_unit"] = metadata.position_unit;
  result["output_position"] = metadata.output_positions;
  result["experiments"] = ExperimentsToList(metadata);
  result["combabc_version"] = metadata.combabc_version;
  result["config_path"] = metadata.config_path;
  result["config_text"] = metadata.config_text;
  result["end_time"] = metadata.end_time;
  return result;
}

py::dict RunConfig(const std::string& config_path,
                   int threads,
                   const std::string& output_directory,
                   bool overwrite,
                   bool report,
                   const std::string& start_from) {
  services::RunRequest request;
  request.config_path = config_path;
  request.start_from = start_from;
  request.output_directory = output_directory;
  request.threads = threads;
  request.overwrite = overwrite;
  request.report = report;
  PythonSignals signals;
  services::RunOutcome outcome;
  {
    const py::gil_scoped_release release;
    outcome = services::RunCalibration(request, &signals);
  }
  signals.RaiseIfInterrupted("combabc: interrupted; continue with combabc.resume(\"" +
                             outcome.history_path + "\")");
  // Read back from the file, so that the arrays are exactly what `combabc export` writes.
  py::dict result = LoadHistory(outcome.history_path);
  result["report_directory"] = outcome.report_directory;
  return result;
}

py::dict Resume(const std::string& history_path,
                int threads,
                bool report,
                std::optional<std::int64_t> max_simulations,
                std::optional<double> max_wall_time,
                std::optional<double> min_acceptance_rate,
                std::optional<double> max_failure_fraction) {
  PythonSignals signals;
  services::RunOutcome outcome;
  {
    const py::gil_scoped_release release;
    services::ResumeRequest request;
    request.history_path = history_path;
    request.threads = threads;
    request.report = report;
    request.limits = {max_simulations, max_wall_time, min_acceptance_rate, max_failure_fraction};
    outcome = services::ResumeCalibration(request, &signals);
  }
  signals.RaiseIfInterrupted("combabc: interrupted; continue with combabc.resume(\"" +
                             outcome.history_path + "\")");
  py::dict result = LoadHistory(outcome.history_path);
  result["report_directory"] = outcome.report_directory;
  return result;
}

py::dict Enumerate(const std::string& config_path,
                   const std::vector<double>& thresholds,
                   int threads,
                   const std::string& output_directory,
                   bool overwrite,
                   bool report,
                   int top,
                   int max_particles) {
  services::EnumerateRequest request;
  request.config_path = config_path;
  request.thresholds = thresholds;
  request.threads = threads;
  request.output_directory = output_directory;
  request.overwrite = overwrite;
  request.report = report;
  request.top = top;
  request.max_particles = max_particles;
  PythonSignals signals;
  services::EnumerateOutcome outcome;
  {
    const py::gil_scoped_release release;
    outcome = services::RunEnumeration(request, &signals);
  }
  signals.RaiseIfInterrupted("combabc: enumeration interrupted; nothing written");
  py::dict result = LoadHistory(outcome.history_path);
  result["report_directory"] = outcome.report_directory;
  py::dict enumeration;
  enumeration["directory"] = outcome.enumeration_directory;
  enumeration["configurations"] = outcome.configurations;
  enumeration["accepted"] = outcome.accepted;
  enumeration["evidence"] = outcome.evidence;
  enumeration["wall_seconds"] = outcome.wall_seconds;
  result["enumeration"] = enumeration;
  return result;
}

py::dict Export(const std::string& history_path,
                const std::string& directory,
                bool overwrite,
                bool netcdf,
                bool all_waves) {
  services::ExportOutcome outcome;
  {
    const py::gil_scoped_release release;
    outcome = services::ExportHistory(history_path, directory, overwrite, netcdf, all_waves);
  }
  py::dict result;
  result["directory"] = outcome.directory;
  result["netcdf_path"] = outcome.netcdf_path;
  result["note"] = outcome.note;
  return result;
}

// The config's simulator at its nominal values (services::NominalSimulator): SensorModel.
std::unique_ptr<services::NominalSimulator> MakeNominal(const std::string& config_path,
                                                        const std::string& work_directory) {
  const py::gil_scoped_release release;
  return std::make_unique<services::NominalSimulator>(LoadConfig(config_path), work_directory);
}

using Bits = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

// bits: uint8[d] or uint8[n, d]; returns float64[m] or float64[n, m].
py::array_t<double> SimulateNominal(const services::NominalSimulator& model, const Bits& bits) {
  const auto d = static_cast<py::ssize_t>(model.dimension());
  const auto m = static_cast<py::ssize_t>(model.output_size());
  const bool single = bits.ndim() == 1;
  if (!(bits.ndim() == 1 || bits.ndim() == 2) || bits.shape(bits.ndim() - 1) != d) {
    throw py::value_error("clamps: expected " + std::to_string(d) + " values of 0/1 per " +
                          "configuration, as an array of shape (" + std::to_string(d) +
                          ",) or (n, " + std::to_string(d) + ")");
  }
  const py::ssize_t n = single ? 1 : bits.shape(0);
  const std::uint8_t* in = bits.data();
  for (py::ssize_t i = 0; i < n * d; ++i) {
    if (in[i] > 1) throw py::value_error("clamps: every value must be 0 or 1");
  }
  py::array_t<double> out = single ? py::array_t<double>(m) : py::array_t<double>({n, m});
  double* values = out.mutable_data();
  {
    const py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) {
      const std::vector<double> w =
          model.Simulate(std::span<const std::uint8_t>(in + i * d, static_cast<std::size_t>(d)));
      std::copy(w.begin(), w.end(), values + i * m);
    }
  }
  return out;
}

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
};

// MultiFidelityOptions as its keywords name them: ValueError naming the argument.
void CheckMultiFidelity(const MultiFidelityOptions& o) {
  auto probability = [](const char* name, double value) {
    if (!(value > 0.0 && value <= 1.0)) {
      throw py::value_error(std::string("MultiFidelityOptions: ") + name + " = " +
                            std::to_string(value) + "; must be in (0, 1]");
    }
  };
  probability("continue_if_accepted", o.continue_if_accepted);
  probability("continue_if_rejected", o.continue_if_rejected);
  probability("floor", o.floor);
  if (!(o.cost_ratio >= 0.0) || !std::isfinite(o.cost_ratio)) {
    throw py::value_error("MultiFidelityOptions: cost_ratio = " + std::to_string(o.cost_ratio) +
                          "; must be > 0 (0: measured)");
  }
}

// MoveOptions as its keywords name them: ValueError naming the argument (MoveOptions::IsValid's
// ranges).
void CheckMoves(const MoveOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw py::value_error(why);
}

// The history of a Python run, opened to continue it: refused (kUsage) for a config run's history,
// a run that has finished (not on a limit), and a problem or options other than the run's.
HistoryStore OpenPythonRun(const std::string& path,
                           const PythonProblem& problem,
                           const SmcOptions& options) {
  const RunMetadata m = HistoryStore::Open(path, /*read_only=*/true).LoadMetadata();
  auto part = [](const std::vector<std::pair<std::string, std::string>>& parts,
                 const std::string& name) {
    for (const auto& [key, digest] : parts) {
      if (key == name) return digest;
    }
    return std::string();
  };
  if (part(m.fingerprint, kPythonFingerprintPart).empty()) {
    throw Error(ErrorKind::kUsage,
                "a config run's history; resume it with combabc.resume(path), without a problem",
                path);
  }
  const auto stop = ParseEnum<Termination>(m.termination);
  const bool on_limit =
      stop &&
      (*stop == Termination::kBudgetExhausted || *stop == Termination::kWallTimeExceeded ||
       *stop == Termination::kAcceptanceRateTooLow || *stop == Termination::kTooManyFailures);
  if (m.status == RunStatus::kFinished && !on_limit) {
    throw Error(ErrorKind::kUsage,
                "the run has already finished (" + m.termination + "); nothing to resume",
                path);
  }
  const auto now = PythonRunFingerprint(problem, options);
  for (const auto& [key, digest] : now) {
    if (part(m.fingerprint, key) != digest) {
      throw Error(ErrorKind::kUsage,
                  std::string(key == kPythonFingerprintPart ? "the problem (space, reals, data, "
                                                              "distance)"
                                                            : "the options") +
                      " differ from the run's: resume it with the problem and options it "
                      "started with (threads and stop limits may change)",
                  path);
    }
  }
  if (on_limit) {
    // Resuming would only record the same stop again: say which limit to raise instead.
    const ResumePoint point = HistoryStore::Open(path, /*read_only=*/true).LoadResumePoint();
    if (const auto again = ImmediateStop(options, point)) {
      const Termination t = again->first;
      const char* keyword = t == Termination::kBudgetExhausted        ? "max_simulations"
                            : t == Termination::kAcceptanceRateTooLow ? "min_acceptance_rate"
                            : t == Termination::kTooManyFailures      ? "max_failure_fraction"
                                                                      : "max_wall_time";
      throw Error(ErrorKind::kUsage,
                  "the run stopped (" + std::string(ToString(t)) + ": " + again->second +
                      ") and would stop again at once; raise the limit with " + keyword + "=",
                  path);
    }
  }
  return HistoryStore::Open(path);
}

// The run's history (when it writes one) and Ctrl-C, as one observer.
class StoredRun final : public SmcObserver {
 public:
  StoredRun(HistoryStore* store, PythonSignals& signals) : store_(store), signals_(signals) {}
  void OnWaveStart(const WaveRecord& wave) override {
    if (store_) store_->OnWaveStart(wave);
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    if (store_) store_->OnBatch(progress, accepted);
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    if (store_) store_->OnWaveEnd(wave);
  }
  bool ShouldStop() override { return signals_.ShouldStop(); }

 private:
  HistoryStore* store_;
  PythonSignals& signals_;
};

// Where a Python run writes: nothing (empty path), a new history (combabc.run with
// output_directory) or the continuation of one (combabc.resume with the problem).
struct PythonRunFile {
  std::string history_path;
  bool overwrite = false;
  bool resume = false;
  bool report = false;
};

// Raises the user's Python exception that ended a run as itself (its type, message and
// traceback), with the engine's line (wave and candidate) attached as a note; else rethrows. A
// KeyboardInterrupt (Ctrl-C that reached Python inside the simulator or distance) is an interrupt
// like one seen between batches: it gets `interrupted`, the note that says how to continue.
[[noreturn]] void RaiseFirstError(const FirstPythonError& first_error,
                                  const std::exception& e,
                                  const std::string& interrupted = "") {
  std::optional<py::error_already_set> raised = first_error.error();
  if (!raised) throw;
  const bool interrupt = raised->matches(PyExc_KeyboardInterrupt);
  const std::string note =
      interrupt && !interrupted.empty() ? interrupted : std::string("combabc: ") + e.what();
  if (py::hasattr(raised->value(), "add_note")) raised->value().attr("add_note")(note);
  throw *raised;
}

py::dict RunSmc(const SmcRequest& request, const PythonRunFile& file) {
  if (request.observed.empty()) {
    throw Error(ErrorKind::kConfig, "the observed data are empty", {}, 0, "observed");
  }
  const py::object simulation_failed =
      py::module_::import("combabc._core").attr("SimulationFailed");
  FirstPythonError first_error;  // outlives the simulator and distance that keep it
  std::unique_ptr<Distance> distance;
  if (request.distance.is_none()) {
    if (!request.components.empty()) {
      throw Error(ErrorKind::kConfig,
                  "components name the values of a distance written in Python; the built-in "
                  "Euclidean distance has one, \"euclidean\"",
                  {},
                  0,
                  "components");
    }
    distance = std::make_unique<EuclideanDistance>(request.observed);
  } else {
    distance = std::make_unique<PythonDistance>(request.distance,
                                                request.distance_batch,
                                                request.components,
                                                request.observed,
                                                simulation_failed,
                                                first_error);
  }
  // Checks the joint priors (CheckJointPrior) before any simulation.
  std::vector<JointPriorGroup> joint;
  for (const auto& [names, prior] : request.priors) joint.push_back({names, prior.prior()});
  const ParameterSpace space(request.space, request.reals, std::move(joint));
  // The default kernel resolved for this space, as the history records it (kind = "auto").
  SmcOptions options = request.options;
  options.proposal = ResolvedProposal(
      options.proposal, AnyUncertainBit(space.binary().free_prior_one()) && space.num_reals() > 0);
  for (const auto& [names, prior] : request.priors) {
    if (prior.error()) prior.error()->Clear();  // what its check or an earlier run raised
  }
  const PythonSimulator simulator(request.simulator,
                                  request.batch,
                                  static_cast<int>(request.observed.size()),
                                  space.num_reals(),
                                  simulation_failed,
                                  request.rng,
                                  first_error);
  std::optional<PythonSimulator> cheap;
  if (options.method == SamplerMethod::kResampleMove) CheckMoves(options.moves);
  if (!request.low_fidelity.is_none()) {
    CheckMultiFidelity(options.multi_fidelity);
    // As a config's [simulator.low_fidelity] with method = "resample_move".
    if (options.method == SamplerMethod::kResampleMove) {
      throw py::value_error(
          "SmcOptions: method = \"resample_move\": moves do not apply to multi-fidelity runs "
          "(Problem(low_fidelity=...)); use method = \"rejection\"");
    }
    cheap.emplace(request.low_fidelity,
                  request.batch,
                  static_cast<int>(request.observed.size()),
                  space.num_reals(),
                  simulation_failed,
                  request.rng,
                  first_error);
  }
  SmcProblem problem;
  problem.space = &space;
  problem.simulator = &simulator;
  problem.distance = distance.get();
  problem.low_fidelity = cheap ? &*cheap : nullptr;
  // The space's reals: a joint real's mean and sd are its prior's, which the fingerprint then
  // holds (a custom prior's functions cannot be fingerprinted; the moments of their draws can).
  const PythonProblem described{.space = &request.space,
                                .reals = &space.reals(),
                                .observed = &request.observed,
                                .components = distance->components(),
                                .batch = request.batch,
                                .rng = request.rng,
                                .python_distance = !request.distance.is_none(),
                                .distance_batch = request.distance_batch,
                                .low_fidelity = !request.low_fidelity.is_none()};
  std::optional<HistoryStore> store;
  std::optional<ResumePoint> resume;
  if (!file.history_path.empty()) {
    const py::gil_scoped_release release;
    if (file.resume) {
      store.emplace(OpenPythonRun(file.history_path, described, options));
      resume = store->BeginResume();
    } else {
      store.emplace(HistoryStore::Create(
          file.history_path, PythonRunMetadata(described, options), file.overwrite));
    }
  }
  PythonSignals signals;
  StoredRun observer(store ? &*store : nullptr, signals);
  const std::string interrupted = file.history_path.empty()
                                      ? "combabc: run interrupted"
                                      : "combabc: interrupted; continue with combabc.resume(\"" +
                                            file.history_path + "\", problem, options)";
  RunHistory history;
  try {
    const py::gil_scoped_release release;
    history = RunCombinatorialSmc(problem, options, &observer, resume ? &*resume : nullptr);
  } catch (const std::exception& e) {
    if (store) {
      try {
        store->MarkFailed(e.what());
      } catch (const std::exception&) {
        // The store itself may be what failed (disk full); the first error is the one to report.
      }
    }
    // A custom prior's own exception, else the simulator's or distance's, as itself.
    for (const auto& [names, prior] : request.priors) {
      if (prior.error() && prior.error()->error()) RaiseFirstError(*prior.error(), e);
    }
    RaiseFirstError(first_error, e, interrupted);
  }
  if (store) {
    const py::gil_scoped_release release;
    store->Finish(history.summary);
    store.reset();  // closed: the history is read back from the file below
  }
  signals.RaiseIfInterrupted(interrupted);
  if (!file.history_path.empty()) {
    // Read back from the file, as a config run's, so that the arrays are what export writes.
    py::dict result = LoadHistory(file.history_path);
    if (file.report) {
      std::string report_directory;
      {
        const py::gil_scoped_release release;
        report_directory = services::WriteReport(file.history_path);
      }
      result["report_directory"] = report_directory;
    }
    return result;
  }
  // Named as a history file of the same run would be.
  const RunMetadata metadata = PythonRunMetadata(described, options);
  py::dict result = HistoryToDict(history, NamesOf(metadata, history));
  result["seed"] = options.seed;
  result["bit_prior_one"] = metadata.bit_prior_one;
  result["real_priors"] = RealPriors(metadata.reals);
  return result;
}

// A bit of BinarySpace(tied=...) by name or by number from 1, as the config's `tie` counts them,
// to its position from 0.
int TiedBit(const py::handle& bit, int dimension, const std::vector<std::string>& names) {
  if (py::isinstance<py::str>(bit)) {
    const auto name = bit.cast<std::string>();
    const auto found = std::find(names.begin(), names.end(), name);
    if (found == names.end()) {
      throw py::value_error("BinarySpace: tied names " + Excerpt(name) +
                            ", which is not one of names");
    }
    return static_cast<int>(found - names.begin());
  }
  // An integer is anything with __index__ (Python's int, NumPy's integer scalars) but a bool:
  // Python's, or NumPy's bool_, whose __index__ NumPy deprecates.
  const std::string type_name = py::str(py::type::of(bit).attr("__name__"));
  if (PyIndex_Check(bit.ptr()) == 0 || py::isinstance<py::bool_>(bit) || type_name == "bool_") {
    throw py::type_error("BinarySpace: tied holds bit names or numbers (from 1), not " + type_name);
  }
  const auto number = bit.cast<long long>();
  if (number < 1 || number > dimension) {
    throw py::value_error("BinarySpace: tied bit " + std::to_string(number) +
                          "; bits are numbered 1 to " + std::to_string(dimension) +
                          " (as the config's tie), or named");
  }
  return static_cast<int>(number - 1);
}

BinarySpace MakeBinarySpace(int dimension,
                            const std::vector<double>& prior_one,
                            double default_prior_one,
                            const std::vector<std::vector<py::object>>& tied_bits,
                            const std::vector<std::string>& names) {
  // The config's bounds on declared bits ([simulator.bits]): at most kMaxBits, distinct names. A
  // ValueError like Python's own, before anything is sized by `dimension`.
  if (dimension > kMaxBits) {
    throw py::value_error("BinarySpace: dimension = " + std::to_string(dimension) + "; at most " +
                          std::to_string(kMaxBits) + " bits");
  }
  std::unordered_map<std::string_view, std::size_t> seen;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto [it, inserted] = seen.emplace(names[k], k);
    if (!inserted) {
      throw py::value_error("BinarySpace: names[" + std::to_string(k) + "] " + Excerpt(names[k]) +
                            " repeats names[" + std::to_string(it->second) + "]");
    }
  }
  std::vector<std::vector<int>> tied;
  for (const auto& group : tied_bits) {
    std::vector<int>& bits = tied.emplace_back();
    for (const py::object& bit : group) bits.push_back(TiedBit(bit, dimension, names));
  }
  BinarySpaceOptions options;
  options.dimension = dimension;
  options.prior_one = prior_one;
  options.default_prior_one = default_prior_one;
  options.tied = tied;
  options.names = names;
  return BinarySpace(options);
}

// SmcOptions.thresholds as Python sets it: a list with, per threshold component, a
// ThresholdSchedule or a list of numbers (a kind = "list" schedule, one threshold per wave); or,
// for one component, a list of numbers. Numbers are Python's or NumPy's (numpy.int64 is no int; an
// array is a list), not bools. Anything else is a TypeError on one line naming what it got, not
// pybind11's listing of overloads.
std::vector<ThresholdSchedule> ThresholdsFrom(const py::handle& value) {
  const py::object real = py::module_::import("numbers").attr("Real");
  auto type_name = [](const py::handle& x) {
    return std::string(py::str(py::type::of(x).attr("__name__")));
  };
  auto is_number = [&](const py::handle& x) {
    return py::isinstance(x, real) && !py::isinstance<py::bool_>(x);
  };
  auto is_list = [](const py::handle& x) {
    return PySequence_Check(x.ptr()) != 0 && !py::isinstance<py::str>(x) &&
           !py::isinstance<py::bytes>(x);
  };
  auto refuse = [&](const std::string& what) {
    throw py::type_error("SmcOptions.thresholds: " + what +
                         "; expected a list of ThresholdSchedule (one per threshold component), "
                         "or of numbers (one per wave) for one component");
  };
  auto numbers = [&](const py::handle& list, const std::string& where) {
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    for (const py::handle& x : py::reinterpret_borrow<py::sequence>(list)) {
      if (!is_number(x)) refuse(where + "holds " + type_name(x) + ", not a number");
      s.values.push_back(x.cast<double>());
    }
    return s;
  };
  if (!is_list(value)) refuse("got " + type_name(value));
  const auto items = py::reinterpret_borrow<py::sequence>(value);
  bool all_numbers = items.size() > 0;
  for (const py::handle& x : items) all_numbers = all_numbers && is_number(x);
  if (all_numbers) return {numbers(value, "")};
  std::vector<ThresholdSchedule> schedules;
  for (std::size_t k = 0; k < items.size(); ++k) {
    const py::object x = items[k];
    if (py::isinstance<ThresholdSchedule>(x)) {
      schedules.push_back(x.cast<ThresholdSchedule>());
    } else if (is_list(x)) {
      schedules.push_back(numbers(x, "[" + std::to_string(k) + "] "));
    } else {
      refuse("[" + std::to_string(k) + "] is " + type_name(x));
    }
  }
  return schedules;
}

// An options struct made from keywords is checked at once, with the engine's message (its
// IsValid) as combabc.Error; fields set later are checked when the run starts (SmcOptions).
void Require(bool valid, const std::string& why) {
  if (!valid) throw Error(ErrorKind::kConfig, why);
}

// The proposal kernels and tempering (SmcOptions::proposal, ::tempering; [proposal] and
// [sampler.tempering] in a config, docs/config.md), their choices by the config's names.
void BindProposalTypes(py::module_& m) {
  const LogisticKernelOptions logistic_defaults;
  py::class_<LogisticKernelOptions>(m, "LogisticKernelOptions")
      .def(py::init([](double min_correlation,
                       int max_predecessors,
                       double ridge,
                       double min_marginal,
                       double clip) {
             LogisticKernelOptions o;
             o.min_correlation = min_correlation;
             o.max_predecessors = max_predecessors;
             o.ridge = ridge;
             o.min_marginal = min_marginal;
             o.clip = clip;
             std::string why;
             Require(o.IsValid(&why), why);
             return o;
           }),
           py::kw_only(),
           py::arg("min_correlation") = logistic_defaults.min_correlation,
           py::arg("max_predecessors") = logistic_defaults.max_predecessors,
           py::arg("ridge") = logistic_defaults.ridge,
           py::arg("min_marginal") = logistic_defaults.min_marginal,
           py::arg("clip") = logistic_defaults.clip)
      .def_readwrite("min_correlation", &LogisticKernelOptions::min_correlation)
      .def_readwrite("max_predecessors", &LogisticKernelOptions::max_predecessors)
      .def_readwrite("ridge", &LogisticKernelOptions::ridge)
      .def_readwrite("min_marginal", &LogisticKernelOptions::min_marginal)
      .def_readwrite("clip", &LogisticKernelOptions::clip)
      .def("is_valid", [](const LogisticKernelOptions& o) {
        std::string why;
        const bool ok = o.IsValid(&why);
        return py::make_tuple(ok, why);
      });

  const ProposalOptions proposal_defaults;
  py::class_<ProposalOptions>(m, "ProposalOptions")
      .def(py::init([](const std::string& kind,
                       const LogisticKernelOptions& logistic,
                       const std::string& continuous,
                       double scale) {
             ProposalOptions o;
             o.binary = Parse<BinaryKernelKind>(kind, "kind");
             o.logistic = logistic;
             o.continuous = Parse<ContinuousKernelKind>(continuous, "continuous");
             o.scale = scale;
             std::string why;
             Require(o.IsValid(&why), why);
             return o;
           }),
           py::kw_only(),
           py::arg("kind") = ToString(proposal_defaults.binary),
           py::arg("logistic") = proposal_defaults.logistic,
           py::arg("continuous") = ToString(proposal_defaults.continuous),
           py::arg("scale") = proposal_defaults.scale)
      .def_property(
          "kind",
          [](const ProposalOptions& o) { return ToString(o.binary); },
          [](ProposalOptions& o, const std::string& text) {
            o.binary = Parse<BinaryKernelKind>(text, "kind");
          })
      .def_readwrite("logistic", &ProposalOptions::logistic)
      .def_property(
          "continuous",
          [](const ProposalOptions& o) { return ToString(o.continuous); },
          [](ProposalOptions& o, const std::string& text) {
            o.continuous = Parse<ContinuousKernelKind>(text, "continuous");
          })
      .def_readwrite("scale", &ProposalOptions::scale)
      .def("is_valid", [](const ProposalOptions& o) {
        std::string why;
        const bool ok = o.IsValid(&why);
        return py::make_tuple(ok, why);
      });

  const TemperingSchedule tempering_defaults;
  py::class_<TemperingSchedule>(m, "TemperingSchedule")
      .def(py::init([](const std::string& kind,
                       const std::string& form,
                       double phi0,
                       std::vector<double> values) {
             TemperingSchedule s;
             s.kind = Parse<TemperingKind>(kind, "kind");
             s.form = Parse<TemperingForm>(form, "form");
             s.phi0 = phi0;
             s.values = std::move(values);
             std::string why;
             Require(s.IsValid("TemperingSchedule", &why), why);
             return s;
           }),
           py::kw_only(),
           py::arg("kind") = ToString(tempering_defaults.kind),
           py::arg("form") = ToString(tempering_defaults.form),
           py::arg("phi0") = tempering_defaults.phi0,
           py::arg("values") = tempering_defaults.values)
      .def_property(
          "kind",
          [](const TemperingSchedule& s) { return ToString(s.kind); },
          [](TemperingSchedule& s, const std::string& text) {
            s.kind = Parse<TemperingKind>(text, "kind");
          })
      .def_property(
          "form",
          [](const TemperingSchedule& s) { return ToString(s.form); },
          [](TemperingSchedule& s, const std::string& text) {
            s.form = Parse<TemperingForm>(text, "form");
          })
      .def_readwrite("phi0", &TemperingSchedule::phi0)
      .def_readwrite("values", &TemperingSchedule::values)
      .def("phi", &TemperingSchedule::Phi, py::arg("wave"), py::arg("planned_waves"))
      .def("is_valid", [](const TemperingSchedule& s) {
        std::string why;
        const bool ok = s.IsValid("TemperingSchedule", &why);
        return py::make_tuple(ok, why);
      });
}

void BindTypes(py::module_& m) {
  py::class_<BinarySpace>(m, "BinarySpace")
      .def(py::init(&MakeBinarySpace),
           py::arg("dimension"),
           py::arg("prior_one") = std::vector<double>{},
           py::arg("default_prior_one") = 0.5,
           py::arg("tied") = std::vector<std::vector<py::object>>{},
           py::arg("names") = std::vector<std::string>{})
      .def_property_readonly("dimension", &BinarySpace::dimension)
      .def_property_readonly("num_free", &BinarySpace::num_free)
      .def_property_readonly("bit_prior_one", &BinarySpace::bit_prior_one)
      .def_property_readonly("names", [](const BinarySpace& s) {
        std::vector<std::string> names;
        names.reserve(static_cast<std::size_t>(s.dimension()));
        for (int k = 0; k < s.dimension(); ++k) names.push_back(s.name(k));
        return names;
      });

  py::class_<ContinuousParameter>(m, "ContinuousParameter")
      .def(py::init(&MakeContinuousParameter),
           py::arg("name"),
           py::arg("kind") = "uniform",
           py::arg("low") = py::none(),
           py::arg("high") = py::none(),
           py::arg("mean") = py::none(),
           py::arg("sd") = py::none())
      .def_readonly("name", &ContinuousParameter::name)
      .def_property_readonly("kind",
                             [](const ContinuousParameter& p) { return ToString(p.prior.kind); })
      .def_property_readonly("low", [](const ContinuousParameter& p) { return p.prior.low; })
      .def_property_readonly("high", [](const ContinuousParameter& p) { return p.prior.high; })
      .def_property_readonly("mean", [](const ContinuousParameter& p) { return p.prior.mean; })
      .def_property_readonly("sd", [](const ContinuousParameter& p) { return p.prior.sd; })
      .def("__repr__", &ContinuousParameterRepr);

  py::class_<ThresholdSchedule>(m, "ThresholdSchedule")
      .def(py::init(&MakeThresholdSchedule),
           py::arg("kind") = "quantile",
           py::arg("values") = std::vector<double>{},
           py::arg("quantile") = 0.5,
           py::arg("initial") = HUGE_VAL,
           py::arg("target") = 0.0,
           py::kw_only(),
           py::arg("weighted") = py::none(),
           py::arg("acceptance_rate") = py::none(),
           py::arg("ess_fraction") = py::none())
      .def_property_readonly("kind", [](const ThresholdSchedule& s) { return ToString(s.kind); })
      .def_readwrite("values", &ThresholdSchedule::values)
      .def_readwrite("quantile", &ThresholdSchedule::quantile)
      .def_readwrite("weighted", &ThresholdSchedule::weighted)
      .def_readwrite("acceptance_rate", &ThresholdSchedule::acceptance_rate)
      .def_readwrite("ess_fraction", &ThresholdSchedule::ess_fraction)
      .def_readwrite("initial", &ThresholdSchedule::initial)
      .def_readwrite("target", &ThresholdSchedule::target);

  BindProposalTypes(m);
  BindBatchRandom(m);  // what a batched simulator with rng=True gets

  // SmcOptions::multi_fidelity ([sampler.multi_fidelity] in a config): used with
  // Problem(low_fidelity=...).
  const MultiFidelityOptions multi_fidelity_defaults;
  py::class_<MultiFidelityOptions>(m, "MultiFidelityOptions")
      .def(py::init([](double continue_if_accepted,
                       double continue_if_rejected,
                       bool adapt,
                       double floor,
                       double cost_ratio) {
             const MultiFidelityOptions o{
                 continue_if_accepted, continue_if_rejected, adapt, floor, cost_ratio};
             CheckMultiFidelity(o);
             return o;
           }),
           py::kw_only(),
           py::arg("continue_if_accepted") = multi_fidelity_defaults.continue_if_accepted,
           py::arg("continue_if_rejected") = multi_fidelity_defaults.continue_if_rejected,
           py::arg("adapt") = multi_fidelity_defaults.adapt,
           py::arg("floor") = multi_fidelity_defaults.floor,
           py::arg("cost_ratio") = multi_fidelity_defaults.cost_ratio)
      .def_readwrite("continue_if_accepted", &MultiFidelityOptions::continue_if_accepted)
      .def_readwrite("continue_if_rejected", &MultiFidelityOptions::continue_if_rejected)
      .def_readwrite("adapt", &MultiFidelityOptions::adapt)
      .def_readwrite("floor", &MultiFidelityOptions::floor)
      .def_readwrite("cost_ratio", &MultiFidelityOptions::cost_ratio);

  // SmcOptions::moves ([sampler.moves] in a config): used with method = "resample_move".
  const MoveOptions move_defaults;
  py::class_<MoveOptions>(m, "MoveOptions")
      .def(py::init([](double ess_fraction,
                       double stay_probability,
                       int max_rounds,
                       double independent_share,
                       double min_survivor_fraction) {
             const MoveOptions o{ess_fraction,
                                 stay_probability,
                                 max_rounds,
                                 independent_share,
                                 min_survivor_fraction};
             CheckMoves(o);
             return o;
           }),
           py::kw_only(),
           py::arg("ess_fraction") = move_defaults.ess_fraction,
           py::arg("stay_probability") = move_defaults.stay_probability,
           py::arg("max_rounds") = move_defaults.max_rounds,
           py::arg("independent_share") = move_defaults.independent_share,
           py::arg("min_survivor_fraction") = move_defaults.min_survivor_fraction)
      .def_readwrite("ess_fraction", &MoveOptions::ess_fraction)
      .def_readwrite("stay_probability", &MoveOptions::stay_probability)
      .def_readwrite("max_rounds", &MoveOptions::max_rounds)
      .def_readwrite("independent_share", &MoveOptions::independent_share)
      .def_readwrite("min_survivor_fraction", &MoveOptions::min_survivor_fraction);

  py::class_<SmcOptions>(m, "SmcOptions")
      .def(py::init<>())
      .def_readwrite("num_waves", &SmcOptions::num_waves)
      .def_readwrite("accepted_per_wave", &SmcOptions::accepted_per_wave)
      .def_readwrite("accepted_by_wave", &SmcOptions::accepted_by_wave)
      .def_property(
          "thresholds",
          [](const SmcOptions& o) { return o.thresholds; },
          [](SmcOptions& o, const py::object& value) { o.thresholds = ThresholdsFrom(value); })
      .def_readwrite("tempering", &SmcOptions::tempering)
      .def_readwrite("proposal", &SmcOptions::proposal)
      .def_property(
          "estimator",
          [](const SmcOptions& o) { return ToString(o.estimator); },
          [](SmcOptions& o, const std::string& text) {
            o.estimator = Parse<Estimator>(text, "estimator");
          })
      .def_readwrite("seed", &SmcOptions::seed)
      .def_readwrite("threads", &SmcOptions::threads)
      .def_readwrite("max_simulations", &SmcOptions::max_simulations)
      .def_readwrite("min_acceptance_rate", &SmcOptions::min_acceptance_rate)
      .def_readwrite("acceptance_floor_after", &SmcOptions::acceptance_floor_after)
      .def_readwrite("max_failure_fraction", &SmcOptions::max_failure_fraction)
      .def_readwrite("failure_fraction_after", &SmcOptions::failure_fraction_after)
      .def_readwrite("max_wall_time_s", &SmcOptions::max_wall_time_s)
      .def_readwrite("batch_size", &SmcOptions::batch_size)
      .def_readwrite("keep_outputs", &SmcOptions::keep_outputs)
      .def_readwrite("multi_fidelity", &SmcOptions::multi_fidelity)
      // "rejection" (the paper's waves) or "resample_move" ([sampler] method in a config).
      .def_property(
          "method",
          [](const SmcOptions& o) { return ToString(o.method); },
          [](SmcOptions& o, const std::string& text) {
            o.method = Parse<SamplerMethod>(text, "method");
          })
      .def_readwrite("moves", &SmcOptions::moves)
      .def("is_valid", [](const SmcOptions& o) {
        std::string why;
        const bool ok = o.IsValid(&why);
        return py::make_tuple(ok, why);
      });
}

}  // namespace
}  // namespace combabc::python

PYBIND11_MODULE(_core, m) {
  using namespace combabc;
  using namespace combabc::python;
  m.doc() = "combabc's compiled core; use the combabc package (docs/python.md)";
  m.attr("__version__") = COMBABC_PYTHON_VERSION;
  // The most bits a BinarySpace (or a config's [simulator.bits]) may declare.
  m.attr("MAX_BITS") = kMaxBits;

  // combabc::Error as combabc.Error, its message as the CLI prints it after "combabc: ".
  static py::exception<Error> error_type(m, "Error", PyExc_RuntimeError);
  // By value: pybind11's ExceptionTranslator is void (*)(std::exception_ptr).
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      const auto type = py::reinterpret_borrow<py::object>(error_type.ptr());
      py::object exception = type(std::string(ToString(e.kind())) + ": " + std::string(e.what()));
      exception.attr("kind") = std::string(ToString(e.kind()));
      exception.attr("exit_code") = ExitCode(e.kind());
      PyErr_SetObject(error_type.ptr(), exception.ptr());
    }
  });
  static py::exception<SimulationFailed> failed_type(m, "SimulationFailed", PyExc_RuntimeError);
  static_cast<void>(failed_type);

  BindTypes(m);
  RegisterPriors(m);
  RegisterModelChoice(m);
  m.def("load_history", &LoadHistory, py::arg("path"));
  m.def("run_config",
        &RunConfig,
        py::arg("config_path"),
        py::arg("threads") = -1,
        py::arg("output_directory") = std::string(),
        py::arg("overwrite") = false,
        py::arg("report") = false,
        py::arg("start_from") = std::string());
  m.def("export",
        &Export,
        py::arg("history_path"),
        py::arg("directory") = std::string(),
        py::arg("overwrite") = false,
        py::arg("netcdf") = true,
        py::arg("all_waves") = false);
  m.def("resume",
        &Resume,
        py::arg("history_path"),
        py::arg("threads") = -1,
        py::arg("report") = false,
        py::arg("max_simulations") = py::none(),
        py::arg("max_wall_time") = py::none(),
        py::arg("min_acceptance_rate") = py::none(),
        py::arg("max_failure_fraction") = py::none());
  m.def("enumerate",
        &Enumerate,
        py::arg("config_path"),
        py::arg("thresholds") = std::vector<double>{},
        py::arg("threads") = -1,
        py::arg("output_directory") = std::string(),
        py::arg("overwrite") = false,
        py::arg("report") = false,
        py::arg("top") = 20,
        py::arg("max_particles") = 100000);
  py::class_<services::NominalSimulator>(m, "NominalSimulator")
      .def(py::init(&MakeNominal), py::arg("config_path"), py::arg("work_directory"))
      .def_property_readonly("dimension", &services::NominalSimulator::dimension)
      .def_property_readonly("positions", &services::NominalSimulator::positions)
      .def_property_readonly("output_name", &services::NominalSimulator::output_name)
      .def_property_readonly("is_sensor", &services::NominalSimulator::is_sensor)
      .def("simulate", &SimulateNominal, py::arg("bits"))
      .def("parse", [](const services::NominalSimulator& model, const std::string& clamps) {
        // The CLI's --clamps check and messages, for a "0110..." string.
        const std::vector<std::uint8_t> bits = model.ParseBits(clamps);
        return py::array_t<std::uint8_t>(static_cast<py::ssize_t>(bits.size()), bits.data());
      });
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
                       py::object low_fidelity) {
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
                               .low_fidelity = std::move(low_fidelity)};
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
           py::arg("low_fidelity") = py::none());
  m.def(
      "run_smc",
      [](const SmcRequest& request,
         const std::string& history_path,
         bool overwrite,
         bool resume,
         bool report) {
        return RunSmc(request,
                      {.history_path = history_path,
                       .overwrite = overwrite,
                       .resume = resume,
                       .report = report});
      },
      py::arg("request"),
      py::arg("history_path") = std::string(),
      py::arg("overwrite") = false,
      py::arg("resume") = false,
      py::arg("report") = false);
}
