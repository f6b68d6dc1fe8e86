#pragma once
// A distance written in Python, for runs started from Python (docs/python.md): d(output, observed)
// -> a number, or k numbers when the problem names k components; batched, d(outputs[n, m],
// observed) -> [n] or [n, k]. The engine calls EvaluateBatch once per batch from its worker
// threads with the GIL released; each call takes the GIL once, for one call of a batched function
// or one call per candidate.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <span>
#include <string>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "python_call.hpp"

namespace combabc::python {

class PythonDistance final : public Distance {
 public:
  // components: the names of its k values (empty: one value named "distance"); observed: the data,
  // passed to every call as one read-only array. simulation_failed: the Python exception type that
  // fails a candidate (combabc.SimulationFailed); any other exception ends the run, kept in
  // `first_error`. Made and destroyed with the GIL held.
  PythonDistance(pybind11::object function,
                 bool batch,
                 std::vector<std::string> components,
                 const std::vector<double>& observed,
                 pybind11::object simulation_failed,
                 FirstPythonError& first_error);
  std::vector<DistanceComponent> components() const override { return components_; }
  // A batch of one; SimulationFailed from the function is thrown as SimulationFailed.
  void Evaluate(std::span<const double> simulated, std::span<double> out) const override;
  // The rows not failed already; SimulationFailed fails the candidate (from a batched function:
  // every candidate of the call). A NaN value is left for the engine to fail.
  void EvaluateBatch(std::span<const double> simulated,
                     std::span<double> out,
                     BatchFailures& failures) const override;

 private:
  pybind11::object function_;
  bool batch_;
  bool named_;  // components given: each result has a component axis
  std::vector<DistanceComponent> components_;
  std::size_t m_;                       // outputs per candidate: the observed data's size
  pybind11::array_t<double> observed_;  // read-only, passed to every call
  pybind11::object simulation_failed_;
  FirstPythonError& first_error_;
};

}  // namespace combabc::python
