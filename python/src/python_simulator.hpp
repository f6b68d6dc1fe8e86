#pragma once
// A simulator written in Python, for runs started from Python (docs/python.md). The engine calls it
// from its worker threads with the GIL released; each call takes the GIL, so Python code runs one
// call at a time while the engine's own work (proposals, distances) stays parallel. The history is
// the same for any thread count: each candidate's parameters come from its own RandomStream.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::python {

// A distance written in Python: d(output, observed) -> a number, or k numbers when the problem
// names k components; batched, d(outputs[n, m], observed) -> [n] or [n, k]. PythonSimulator calls
// it right after the simulator, while it holds the GIL (one hand-over per batch for both), and
// appends its k values to each output row; TailDistance hands them to the engine. Made and
// destroyed with the GIL held.
class PythonDistance {
 public:
  PythonDistance(pybind11::object function,
                 bool batch,
                 std::vector<std::string> components,
                 const std::vector<double>& observed);
  std::size_t num_components() const { return names_.size(); }
  const std::vector<std::string>& names() const { return names_; }
  // rows: n rows of `width` values, the simulator's m outputs first; writes the k distances after
  // them. Skips candidates already failed or whose output holds NaN (the engine fails those);
  // a NaN distance or SimulationFailed fails the candidate. Other Python exceptions propagate as
  // error_already_set. GIL held.
  void Measure(std::span<double> rows,
               std::size_t width,
               std::size_t m,
               BatchFailures& failures,
               const pybind11::handle& simulation_failed) const;

 private:
  pybind11::object function_;
  bool batch_;
  bool named_;  // components given: each result has a component axis
  std::vector<std::string> names_;
  pybind11::array_t<double> observed_;  // read-only, passed to every call
};

// The engine's side of a PythonDistance: the k values the simulator appended after its m outputs.
class TailDistance final : public Distance {
 public:
  TailDistance(std::vector<std::string> names, std::size_t m);
  std::vector<DistanceComponent> components() const override { return components_; }
  void Evaluate(std::span<const double> simulated, std::span<double> out) const override;

 private:
  std::vector<DistanceComponent> components_;
  std::size_t m_;
};

class PythonSimulator final : public Simulator {
 public:
  // function: f(bits) or f(bits, reals) (reals only when num_reals > 0). Per sample (batch =
  // false) bits is uint8[d], reals float64[r], and f returns m values; batched, bits is
  // uint8[n, d], reals float64[n, r], and f returns an [n, m] array. simulation_failed: the Python
  // exception type that marks one candidate failed (combabc.SimulationFailed). with_rng: f also
  // gets the keyword argument rng, a numpy Generator seeded from the candidate's own RandomStream
  // (batched: a list of n of them), so that a stochastic simulator gives the same history for any
  // thread count and batch size. distance: a Python distance whose values follow the m outputs
  // of each row (output_size() is then m + k), or null. Made and destroyed with the GIL held.
  PythonSimulator(pybind11::object function,
                  bool batch,
                  int output_size,
                  int num_reals,
                  pybind11::object simulation_failed,
                  bool with_rng = false,
                  const PythonDistance* distance = nullptr);
  int output_size() const override { return width_; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;
  // The first exception the simulator or distance raised that ended the run (not
  // SimulationFailed), if any: the caller raises it again in Python once the run has returned.
  // Read with the GIL held.
  std::optional<pybind11::error_already_set> python_error() const;

 private:
  // Call f (GIL held) for the whole batch / one candidate; a wrong output shape raises ValueError.
  // Python exceptions propagate as error_already_set.
  void CallBatch(const ParameterBatch& batch,
                 std::span<RandomStream> rngs,
                 std::span<double> out) const;
  void CallOne(const ParameterView& theta, RandomStream& rng, std::span<double> out) const;
  // The distance of rows already simulated; a Python exception ends the run (Fatal).
  void Measure(std::span<double> out, BatchFailures& failures) const;
  // f(args..., rng=...) when with_rng, else f(args...).
  pybind11::object Call(const pybind11::tuple& args, const pybind11::object& rng) const;
  // A numpy Generator seeded with two 64-bit words drawn from `rng`.
  pybind11::object Generator(RandomStream& rng) const;
  // Keeps the first error and throws a C++ exception that ends the run; who: "simulator" or
  // "distance".
  [[noreturn]] void Fatal(pybind11::error_already_set& error, const char* who) const;

  pybind11::object function_;
  bool batch_;
  int output_size_;  // m, what the function returns per candidate
  int width_;        // m + the distance's k
  int num_reals_;
  pybind11::object simulation_failed_;
  bool with_rng_;
  pybind11::object default_rng_;  // numpy.random.default_rng, when with_rng
  const PythonDistance* distance_;
  mutable std::mutex mutex_;
  mutable std::optional<pybind11::error_already_set> error_;
};

}  // namespace combabc::python
