#pragma once
// What the Python simulator and the Python distance of a run (python_simulator.hpp,
// python_distance.hpp) share: checking what a Python function returned, and keeping the first
// Python exception that ended the run, so that the caller raises it again as itself.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace combabc::python {

using Doubles = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;

// The function's result as a C-contiguous float64 array of the expected shape ({} for a number),
// or ValueError / TypeError (raised as error_already_set) naming what came back; who: "simulator"
// or "distance". GIL held.
Doubles Checked(const pybind11::object& result,
                const std::vector<pybind11::ssize_t>& expected,
                const char* who);

// The first Python exception (not SimulationFailed) that ended a run, shared by the run's Python
// simulator and distance (a custom prior has its own). Made and destroyed with the GIL held; the
// methods too.
class FirstPythonError {
 public:
  // Keeps `error` unless one is kept already, and throws the C++ exception that ends the run
  // ("the Python <who> raised <type>: <message>"); who: "simulator" or "distance".
  [[noreturn]] void Keep(pybind11::error_already_set& error, const char* who);
  // Keeps `error` unless one is kept already, and returns its one line ("<type>: <message>"):
  // for a caller that throws its own exception (a custom prior's combabc::Error).
  std::string Remember(pybind11::error_already_set& error, const char* who);
  // Forgets the kept error: a custom prior keeps its own, and may serve several runs.
  void Clear();
  // Throws once one is kept: no Python function is called after the run's first error.
  void ThrowIfKept() const;
  // The caller raises it again in Python once the run has returned.
  std::optional<pybind11::error_already_set> error() const;

 private:
  mutable std::mutex mutex_;
  std::optional<pybind11::error_already_set> error_;
  std::string who_;
};

}  // namespace combabc::python
