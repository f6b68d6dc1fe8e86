// combabc._core's proposal kernels and tempering (SmcOptions::proposal, ::tempering).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "combabc/samplers/smc_options.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

// An options struct made from keywords is checked at once, with the engine's message (its
// IsValid) as combabc.Error; fields set later are checked when the run starts (SmcOptions).
void Require(bool valid, const std::string& why) {
  if (!valid) throw Error(ErrorKind::kConfig, why);
}

}  // namespace

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

}  // namespace combabc::python
