// combabc._core.answer(path): the answer of a history file, computed by the one function that the
// terminal and summary.json use (SummariseAnswer, through services::ReadAnswer), so that
// History.answer() shows their numbers rather than a second computation of them.
#include "answer_binding.hpp"

#include <pybind11/stl.h>

#include <optional>
#include <string>

#include "combabc/services/history_tools.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

py::dict BitDict(const AnswerBit& b) {
  py::dict bit;
  bit["number"] = b.number;
  bit["name"] = b.name;
  bit["position"] = b.position ? py::object(py::str(b.position->Text())) : py::none();
  bit["p_one"] = b.p_one;
  bit["mc_se"] = b.mc_se;
  bit["verdict"] = std::string(ToString(b.verdict));
  return bit;
}

py::dict RealDict(const AnswerReal& r) {
  py::dict real;
  real["name"] = r.name;
  real["mean"] = r.mean;
  real["mc_se"] = r.mc_se;
  real["sd"] = r.sd;
  real["sd_se"] = r.sd_se;
  real["ess"] = r.ess;
  real["q05"] = r.q05;
  real["median"] = r.median;
  real["q95"] = r.q95;
  return real;
}

py::dict ConfigurationDict(const AnswerConfiguration& c) {
  py::dict configuration;
  configuration["bits"] = c.bits;
  configuration["mass"] = c.mass;
  configuration["mass_se"] = c.mass_se ? py::object(py::float_(*c.mass_se)) : py::none();
  configuration["fixed"] = c.fixed;
  return configuration;
}

}  // namespace

py::dict AnswerToDict(const Answer& a) {
  py::dict out;
  out["wave"] = a.wave;
  out["waves"] = a.waves;
  out["complete"] = a.complete;
  out["exact"] = a.exact;
  out["estimator"] = a.estimator;
  out["termination"] = a.termination;
  out["verdict_level"] = a.verdict_level;
  out["particles"] = a.particles;
  out["distinct"] = a.distinct;
  out["tempered"] = a.tempered;
  py::list temperatures;
  for (const AnswerTemperature& t : a.temperatures) {
    temperatures.append(py::make_tuple(t.component, t.temperature));
  }
  out["temperatures"] = temperatures;
  py::list bits;
  for (const AnswerBit& b : a.bits) bits.append(BitDict(b));
  out["bits"] = bits;
  py::list reals;
  for (const AnswerReal& r : a.reals) reals.append(RealDict(r));
  out["reals"] = reals;
  py::list configurations;
  for (const AnswerConfiguration& c : a.top_configurations) {
    configurations.append(ConfigurationDict(c));
  }
  out["top_configurations"] = configurations;
  out["text"] = AnswerText(a);
  return out;
}

void BindAnswer(py::module_& m) {
  m.def(
      "answer",
      [](const std::string& path) {
        Answer answer;
        {
          const py::gil_scoped_release release;
          answer = services::ReadAnswer(path);
        }
        return AnswerToDict(answer);
      },
      py::arg("path"),
      "The answer of a history file as a dict (AnswerToDict): the terminal's and summary.json's "
      "numbers.");
}

}  // namespace combabc::python
