#include "python_simulator.hpp"

#include <pybind11/numpy.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

namespace py = pybind11;

namespace combabc::python {
namespace {

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string Shape(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) {
    text += (k ? ", " : "") + std::to_string(a.shape(k));
  }
  return text + (a.ndim() == 1 ? ",)" : ")");
}

// The function's result as a C-contiguous float64 array of the expected shape, or ValueError /
// TypeError (raised as error_already_set) naming what came back.
Doubles Checked(const py::object& result, std::vector<py::ssize_t> expected) {
  Doubles values = Doubles::ensure(result);
  if (!values) {
    PyErr_Format(PyExc_TypeError,
                 "the simulator returned %s, not an array of numbers",
                 Py_TYPE(result.ptr())->tp_name);
    throw py::error_already_set();
  }
  const bool same = values.ndim() == static_cast<py::ssize_t>(expected.size()) &&
                    std::equal(expected.begin(), expected.end(), values.shape());
  if (!same) {
    std::string want = "(";
    for (std::size_t k = 0; k < expected.size(); ++k) {
      want += (k ? ", " : "") + std::to_string(expected[k]);
    }
    want += expected.size() == 1 ? ",)" : ")";
    const std::string message =
        "the simulator returned an array of shape " + Shape(values) + ", expected " + want;
    PyErr_SetString(PyExc_ValueError, message.c_str());
    throw py::error_already_set();
  }
  return values;
}

}  // namespace

PythonSimulator::PythonSimulator(py::object function,
                                 bool batch,
                                 int output_size,
                                 int num_reals,
                                 py::object simulation_failed,
                                 bool with_rng)
    : function_(std::move(function)),
      batch_(batch),
      output_size_(output_size),
      num_reals_(num_reals),
      simulation_failed_(std::move(simulation_failed)),
      with_rng_(with_rng) {
  if (with_rng_) default_rng_ = py::module_::import("numpy.random").attr("default_rng");
}

py::object PythonSimulator::Generator(RandomStream& rng) const {
  // Two words: a SeedSequence of 128 bits, so distinct candidates never share a generator.
  const std::uint64_t a = rng.Next();
  const std::uint64_t b = rng.Next();
  return default_rng_(py::make_tuple(a, b));
}

py::object PythonSimulator::Call(const py::tuple& args, const py::object& rng) const {
  if (!with_rng_) return function_(*args);
  return function_(*args, py::arg("rng") = rng);
}

std::optional<py::error_already_set> PythonSimulator::python_error() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

void PythonSimulator::Fatal(py::error_already_set& error) const {
  std::string text = py::str(error.type().attr("__name__"));
  text += ": " + std::string(py::str(error.value()));
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = error;
  }
  throw std::runtime_error("the Python simulator raised " + text);
}

void PythonSimulator::CallOne(const ParameterView& theta,
                              RandomStream& rng,
                              std::span<double> out) const {
  py::array_t<std::uint8_t> bits(static_cast<py::ssize_t>(theta.bits.size()), theta.bits.data());
  const py::object generator = with_rng_ ? Generator(rng) : py::none();
  py::object result;
  if (num_reals_ > 0) {
    py::array_t<double> reals(static_cast<py::ssize_t>(theta.reals.size()), theta.reals.data());
    result = Call(py::make_tuple(bits, reals), generator);
  } else {
    result = Call(py::make_tuple(bits), generator);
  }
  const Doubles values = Checked(result, {static_cast<py::ssize_t>(out.size())});
  std::memcpy(out.data(), values.data(), out.size() * sizeof(double));
}

void PythonSimulator::CallBatch(const ParameterBatch& batch,
                                std::span<RandomStream> rngs,
                                std::span<double> out) const {
  const auto n = static_cast<py::ssize_t>(batch.count);
  py::object generators = py::none();
  if (with_rng_) {
    py::list list;
    for (std::size_t i = 0; i < batch.count; ++i) list.append(Generator(rngs[i]));
    generators = list;
  }
  py::array_t<std::uint8_t> bits({n, static_cast<py::ssize_t>(batch.num_bits)});
  std::memcpy(bits.mutable_data(), batch.bits.data(), batch.bits.size_bytes());
  py::object result;
  if (num_reals_ > 0) {
    py::array_t<double> reals({n, static_cast<py::ssize_t>(batch.num_reals)});
    std::memcpy(reals.mutable_data(), batch.reals.data(), batch.reals.size_bytes());
    result = Call(py::make_tuple(bits, reals), generators);
  } else {
    result = Call(py::make_tuple(bits), generators);
  }
  const Doubles values = Checked(result, {n, static_cast<py::ssize_t>(output_size_)});
  std::memcpy(out.data(), values.data(), out.size() * sizeof(double));
}

void PythonSimulator::Simulate(const ParameterView& theta,
                               RandomStream& rng,
                               std::span<double> out) const {
  const py::gil_scoped_acquire gil;
  try {
    CallOne(theta, rng, out);
  } catch (py::error_already_set& e) {
    if (e.matches(simulation_failed_)) throw SimulationFailed(py::str(e.value()));
    Fatal(e);
  }
}

void PythonSimulator::SimulateBatch(const ParameterBatch& batch,
                                    std::span<RandomStream> rngs,
                                    std::span<double> out,
                                    BatchFailures& failures) const {
  const std::size_t m = static_cast<std::size_t>(output_size_);
  // One GIL hand-over per batch, not per candidate.
  const py::gil_scoped_acquire gil;
  if (python_error()) throw std::runtime_error("the Python simulator raised earlier");
  if (batch_) {
    try {
      CallBatch(batch, rngs, out);
    } catch (py::error_already_set& e) {
      if (!e.matches(simulation_failed_)) Fatal(e);
      // SimulationFailed from a batch call: every candidate of the call failed.
      const std::string reason = py::str(e.value());
      for (std::size_t i = 0; i < batch.count; ++i) failures.Fail(i, reason);
    }
    return;
  }
  for (std::size_t i = 0; i < batch.count; ++i) {
    try {
      CallOne(batch[i], rngs[i], out.subspan(i * m, m));
    } catch (py::error_already_set& e) {
      if (!e.matches(simulation_failed_)) Fatal(e);
      failures.Fail(i, std::string(py::str(e.value())));
    }
  }
}

}  // namespace combabc::python
