#include "python_simulator.hpp"

#include <pybind11/numpy.h>

#include <algorithm>
#include <array>
#include <cmath>
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
// TypeError (raised as error_already_set) naming what came back; who: "simulator" or "distance".
Doubles Checked(const py::object& result, std::vector<py::ssize_t> expected, const char* who) {
  Doubles values = Doubles::ensure(result);
  if (!values) {
    PyErr_Format(PyExc_TypeError,
                 "the %s returned %s, not an array of numbers",
                 who,
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
    want += expected.size() == 1 ? ",)" : ")";  // () for a number
    const std::string message = std::string("the ") + who + " returned an array of shape " +
                                Shape(values) + ", expected " + want;
    PyErr_SetString(PyExc_ValueError, message.c_str());
    throw py::error_already_set();
  }
  return values;
}

bool HoldsNan(std::span<const double> values) {
  return std::any_of(values.begin(), values.end(), [](double v) { return std::isnan(v); });
}

}  // namespace

PythonDistance::PythonDistance(py::object function,
                               bool batch,
                               std::vector<std::string> components,
                               const std::vector<double>& observed)
    : function_(std::move(function)),
      batch_(batch),
      named_(!components.empty()),
      names_(components.empty() ? std::vector<std::string>{"distance"} : std::move(components)),
      observed_(static_cast<py::ssize_t>(observed.size()), observed.data()) {
  // One array for every call: read-only, so that a distance cannot change the data it is given.
  observed_.attr("setflags")(py::arg("write") = false);
}

void PythonDistance::Measure(std::span<double> rows,
                             std::size_t width,
                             std::size_t m,
                             BatchFailures& failures,
                             const py::handle& simulation_failed) const {
  const std::size_t n = failures.size();
  const std::size_t k = names_.size();
  std::vector<std::size_t> measured;  // the candidates the distance sees, in index order
  for (std::size_t i = 0; i < n; ++i) {
    if (!failures.failed(i) && !HoldsNan(rows.subspan(i * width, m))) measured.push_back(i);
  }
  auto store = [&](std::size_t i, const double* values) {
    std::copy(values, values + k, rows.begin() + static_cast<std::ptrdiff_t>(i * width + m));
    for (std::size_t j = 0; j < k; ++j) {
      // The engine's own reason for a NaN distance (samplers/candidate_batch.cpp).
      if (std::isnan(values[j])) {
        failures.Fail(i, "distance component " + std::to_string(j) + " is NaN");
        break;
      }
    }
  };
  const auto km = static_cast<py::ssize_t>(k);
  if (batch_) {
    if (measured.empty()) return;
    const auto count = static_cast<py::ssize_t>(measured.size());
    py::array_t<double> outputs({count, static_cast<py::ssize_t>(m)});
    double* to = outputs.mutable_data();
    for (const std::size_t i : measured) {
      to = std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>(i * width), m, to);
    }
    Doubles values;
    try {
      values = Checked(function_(outputs, observed_),
                       named_ ? std::vector<py::ssize_t>{count, km} : std::vector{count},
                       "distance");
    } catch (py::error_already_set& e) {
      if (!e.matches(simulation_failed)) throw;
      // SimulationFailed from a batch call: every candidate of the call failed.
      const std::string reason = py::str(e.value());
      for (const std::size_t i : measured) failures.Fail(i, reason);
      return;
    }
    for (std::size_t r = 0; r < measured.size(); ++r) store(measured[r], values.data() + r * k);
    return;
  }
  for (const std::size_t i : measured) {
    py::array_t<double> output(static_cast<py::ssize_t>(m), rows.data() + i * width);
    try {
      const Doubles values = Checked(function_(output, observed_),
                                     named_ ? std::vector{km} : std::vector<py::ssize_t>{},
                                     "distance");
      store(i, values.data());
    } catch (py::error_already_set& e) {
      if (!e.matches(simulation_failed)) throw;
      failures.Fail(i, std::string(py::str(e.value())));
    }
  }
}

TailDistance::TailDistance(std::vector<std::string> names, std::size_t m) : m_(m) {
  for (std::string& name : names) {
    components_.push_back({std::move(name), ComponentKind::kThreshold, 1.0});
  }
}

void TailDistance::Evaluate(std::span<const double> simulated, std::span<double> out) const {
  const auto tail = simulated.subspan(m_, out.size());
  std::copy(tail.begin(), tail.end(), out.begin());
}

PythonSimulator::PythonSimulator(py::object function,
                                 bool batch,
                                 int output_size,
                                 int num_reals,
                                 py::object simulation_failed,
                                 bool with_rng,
                                 const PythonDistance* distance)
    : function_(std::move(function)),
      batch_(batch),
      output_size_(output_size),
      width_(output_size + (distance ? static_cast<int>(distance->num_components()) : 0)),
      num_reals_(num_reals),
      simulation_failed_(std::move(simulation_failed)),
      with_rng_(with_rng),
      distance_(distance) {
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

void PythonSimulator::Fatal(py::error_already_set& error, const char* who) const {
  std::string text = py::str(error.type().attr("__name__"));
  text += ": " + std::string(py::str(error.value()));
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = error;
  }
  throw std::runtime_error(std::string("the Python ") + who + " raised " + text);
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
  const auto m = static_cast<std::size_t>(output_size_);
  const Doubles values = Checked(result, {static_cast<py::ssize_t>(m)}, "simulator");
  std::memcpy(out.data(), values.data(), m * sizeof(double));
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
  const auto m = static_cast<std::size_t>(output_size_);
  const auto width = static_cast<std::size_t>(width_);
  const Doubles values = Checked(result, {n, static_cast<py::ssize_t>(m)}, "simulator");
  for (std::size_t i = 0; i < batch.count; ++i) {
    std::memcpy(out.data() + i * width, values.data() + i * m, m * sizeof(double));
  }
}

void PythonSimulator::Measure(std::span<double> out, BatchFailures& failures) const {
  if (!distance_) return;
  try {
    distance_->Measure(out,
                       static_cast<std::size_t>(width_),
                       static_cast<std::size_t>(output_size_),
                       failures,
                       simulation_failed_);
  } catch (py::error_already_set& e) {
    Fatal(e, "distance");
  }
}

void PythonSimulator::Simulate(const ParameterView& theta,
                               RandomStream& rng,
                               std::span<double> out) const {
  const py::gil_scoped_acquire gil;
  try {
    CallOne(theta, rng, out);
  } catch (py::error_already_set& e) {
    if (e.matches(simulation_failed_)) throw SimulationFailed(py::str(e.value()));
    Fatal(e, "simulator");
  }
  // A batch of one, so that a failed distance is this candidate's SimulationFailed.
  std::array<std::uint8_t, 1> status{};
  std::vector<char> reason(kFailureReasonBytes, '\0');
  BatchFailures failures{std::span(status), std::span(reason)};
  Measure(out, failures);
  if (failures.failed(0)) throw SimulationFailed(std::string(failures.reason(0)));
}

void PythonSimulator::SimulateBatch(const ParameterBatch& batch,
                                    std::span<RandomStream> rngs,
                                    std::span<double> out,
                                    BatchFailures& failures) const {
  const auto width = static_cast<std::size_t>(width_);
  // One GIL hand-over per batch, not per candidate, for the simulator and the distance.
  const py::gil_scoped_acquire gil;
  if (python_error()) throw std::runtime_error("the Python simulator raised earlier");
  if (batch_) {
    try {
      CallBatch(batch, rngs, out);
    } catch (py::error_already_set& e) {
      if (!e.matches(simulation_failed_)) Fatal(e, "simulator");
      // SimulationFailed from a batch call: every candidate of the call failed.
      const std::string reason = py::str(e.value());
      for (std::size_t i = 0; i < batch.count; ++i) failures.Fail(i, reason);
    }
  } else {
    for (std::size_t i = 0; i < batch.count; ++i) {
      try {
        CallOne(batch[i], rngs[i], out.subspan(i * width, width));
      } catch (py::error_already_set& e) {
        if (!e.matches(simulation_failed_)) Fatal(e, "simulator");
        failures.Fail(i, std::string(py::str(e.value())));
      }
    }
  }
  Measure(out, failures);
}

}  // namespace combabc::python
