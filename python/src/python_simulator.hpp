#pragma once
// A simulator written in Python, for runs started from Python (docs/python.md). The engine calls it
// from its worker threads with the GIL released; each call takes the GIL, so Python code runs one
// call at a time while the engine's own work (proposals, distances) stays parallel. The history is
// the same for any thread count: each candidate's parameters come from its own RandomStream.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <span>

#include "combabc/samplers/simulator.hpp"
#include "python_call.hpp"

namespace combabc::python {

class PythonSimulator final : public Simulator {
 public:
  // function: f(bits) or f(bits, reals) (reals only when num_reals > 0). Per sample (batch =
  // false) bits is uint8[d], reals float64[r], and f returns m values; batched, bits is
  // uint8[n, d], reals float64[n, r], and f returns an [n, m] array. simulation_failed: the Python
  // exception type that marks one candidate failed (combabc.SimulationFailed); any other exception
  // ends the run, kept in `first_error`. with_rng: f also gets the keyword argument rng, a numpy
  // Generator seeded from the candidate's own RandomStream (batched: a BatchRandom over the batch's
  // candidates, batch_random.hpp), so that a stochastic simulator gives the same history for any
  // thread count and batch size. Made and destroyed with the GIL held.
  PythonSimulator(pybind11::object function,
                  bool batch,
                  int output_size,
                  int num_reals,
                  pybind11::object simulation_failed,
                  bool with_rng,
                  FirstPythonError& first_error);
  int output_size() const override { return output_size_; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;

 private:
  // Call f (GIL held) for the whole batch / one candidate; a wrong output shape raises ValueError.
  // Python exceptions propagate as error_already_set.
  void CallBatch(const ParameterBatch& batch,
                 std::span<RandomStream> rngs,
                 std::span<double> out) const;
  void CallOne(const ParameterView& theta, RandomStream& rng, std::span<double> out) const;
  // f(args..., rng=...) when with_rng, else f(args...).
  pybind11::object Call(const pybind11::tuple& args, const pybind11::object& rng) const;

  pybind11::object function_;
  bool batch_;
  int output_size_;  // m, what the function returns per candidate
  int num_reals_;
  pybind11::object simulation_failed_;
  bool with_rng_;
  pybind11::object default_rng_;  // numpy.random.default_rng, when with_rng
  FirstPythonError& first_error_;
};

}  // namespace combabc::python
