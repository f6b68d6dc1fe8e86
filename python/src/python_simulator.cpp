#include "python_simulator.hpp"

#include <pybind11/numpy.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <utility>

#include "batch_random.hpp"

namespace py = pybind11;

namespace combabc::python {

PythonSimulator::PythonSimulator(py::object function,
                                 bool batch,
                                 int output_size,
                                 int num_reals,
                                 py::object simulation_failed,
                                 bool with_rng,
                                 FirstPythonError& first_error)
    : function_(std::move(function)),
      batch_(batch),
      output_size_(output_size),
      num_reals_(num_reals),
      simulation_failed_(std::move(simulation_failed)),
      with_rng_(with_rng),
      first_error_(first_error) {
  if (with_rng_) default_rng_ = py::module_::import("numpy.random").attr("default_rng");
}

py::object PythonSimulator::Call(const py::tuple& args, const py::object& rng) const {
  if (!with_rng_) return function_(*args);
  return function_(*args, py::arg("rng") = rng);
}

void PythonSimulator::CallOne(const ParameterView& theta,
                              RandomStream& rng,
                              std::span<double> out) const {
  py::array_t<std::uint8_t> bits(static_cast<py::ssize_t>(theta.bits.size()), theta.bits.data());
  const py::object generator = with_rng_ ? NumpyGenerator(default_rng_, DrawSeed(rng)) : py::none();
  py::object result;
  if (num_reals_ > 0) {
    py::array_t<double> reals(static_cast<py::ssize_t>(theta.reals.size()), theta.reals.data());
    result = Call(py::make_tuple(bits, reals), generator);
  } else {
    result = Call(py::make_tuple(bits), generator);
  }
  const auto m = static_cast<std::size_t>(output_size_);
  const Doubles values = Checked(result, {static_cast<py::ssize_t>(m)}, "simulator");
  std::memcpy(out.data(), values.data(), m * sizeof(double));
}

void PythonSimulator::CallBatch(const ParameterBatch& batch,
                                std::span<RandomStream> rngs,
                                std::span<double> out) const {
  const auto n = static_cast<py::ssize_t>(batch.count);
  const py::object random =
      with_rng_ ? py::cast(BatchRandom(rngs.first(batch.count), default_rng_)) : py::none();
  py::array_t<std::uint8_t> bits({n, static_cast<py::ssize_t>(batch.num_bits)});
  std::memcpy(bits.mutable_data(), batch.bits.data(), batch.bits.size_bytes());
  py::object result;
  if (num_reals_ > 0) {
    py::array_t<double> reals({n, static_cast<py::ssize_t>(batch.num_reals)});
    std::memcpy(reals.mutable_data(), batch.reals.data(), batch.reals.size_bytes());
    result = Call(py::make_tuple(bits, reals), random);
  } else {
    result = Call(py::make_tuple(bits), random);
  }
  const auto m = static_cast<std::size_t>(output_size_);
  const Doubles values = Checked(result, {n, static_cast<py::ssize_t>(m)}, "simulator");
  std::memcpy(out.data(), values.data(), batch.count * m * sizeof(double));
}

void PythonSimulator::Simulate(const ParameterView& theta,
                               RandomStream& rng,
                               std::span<double> out) const {
  const py::gil_scoped_acquire gil;
  try {
    CallOne(theta, rng, out);
  } catch (py::error_already_set& e) {
    if (e.matches(simulation_failed_)) throw SimulationFailed(py::str(e.value()));
    first_error_.Keep(e, "simulator");
  }
}

void PythonSimulator::SimulateBatch(const ParameterBatch& batch,
                                    std::span<RandomStream> rngs,
                                    std::span<double> out,
                                    BatchFailures& failures) const {
  const auto m = static_cast<std::size_t>(output_size_);
  // One GIL hand-over per batch, not per candidate.
  const py::gil_scoped_acquire gil;
  first_error_.ThrowIfKept();
  if (batch_) {
    try {
      CallBatch(batch, rngs, out);
    } catch (py::error_already_set& e) {
      if (!e.matches(simulation_failed_)) first_error_.Keep(e, "simulator");
      // SimulationFailed from a batch call: every candidate of the call failed.
      const std::string reason = py::str(e.value());
      for (std::size_t i = 0; i < batch.count; ++i) failures.Fail(i, reason);
    }
  } else {
    for (std::size_t i = 0; i < batch.count; ++i) {
      try {
        CallOne(batch[i], rngs[i], out.subspan(i * m, m));
      } catch (py::error_already_set& e) {
        if (!e.matches(simulation_failed_)) first_error_.Keep(e, "simulator");
        failures.Fail(i, std::string(py::str(e.value())));
      }
    }
  }
}

}  // namespace combabc::python
