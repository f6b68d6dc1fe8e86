// combabc._core's parameter and options types: BinarySpace, ContinuousParameter, ThresholdSchedule,
// SmcOptions and the options tables it holds (the proposal kernels are bind_proposals.cpp's).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "batch_random.hpp"
#include "bindings.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/smc_options.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

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

// The parameter space and the thresholds (a config's [simulator.bits], [parameters.*] and
// [thresholds]).
void BindSpaces(py::module_& m) {
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
}

// SmcOptions and the options it holds (a config's [sampler] and its tables).
void BindOptions(py::module_& m) {
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
                       double min_survivor_fraction,
                       const std::string& final_wave) {
             const MoveOptions o{ess_fraction,
                                 stay_probability,
                                 max_rounds,
                                 independent_share,
                                 min_survivor_fraction,
                                 Parse<FinalWave>(final_wave, "final_wave")};
             CheckMoves(o);
             return o;
           }),
           py::kw_only(),
           py::arg("ess_fraction") = move_defaults.ess_fraction,
           py::arg("stay_probability") = move_defaults.stay_probability,
           py::arg("max_rounds") = move_defaults.max_rounds,
           py::arg("independent_share") = move_defaults.independent_share,
           py::arg("min_survivor_fraction") = move_defaults.min_survivor_fraction,
           py::arg("final_wave") = std::string(ToString(move_defaults.final_wave)))
      .def_readwrite("ess_fraction", &MoveOptions::ess_fraction)
      .def_readwrite("stay_probability", &MoveOptions::stay_probability)
      .def_readwrite("max_rounds", &MoveOptions::max_rounds)
      .def_readwrite("independent_share", &MoveOptions::independent_share)
      .def_readwrite("min_survivor_fraction", &MoveOptions::min_survivor_fraction)
      // "auto", "always" or "never" (docs/algorithm.md, "The final wave").
      .def_property(
          "final_wave",
          [](const MoveOptions& o) { return ToString(o.final_wave); },
          [](MoveOptions& o, const std::string& text) {
            o.final_wave = Parse<FinalWave>(text, "final_wave");
          });

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

void BindTypes(py::module_& m) {
  BindSpaces(m);
  BindProposalTypes(m);
  BindBatchRandom(m);  // what a batched simulator with rng=True gets
  BindOptions(m);
}

}  // namespace combabc::python
