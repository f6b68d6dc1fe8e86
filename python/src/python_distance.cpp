#include "python_distance.hpp"

#include <algorithm>
#include <utility>

#include "combabc/core/check.hpp"
#include "combabc/samplers/simulator.hpp"

namespace py = pybind11;

namespace combabc::python {

PythonDistance::PythonDistance(py::object function,
                               bool batch,
                               std::vector<std::string> components,
                               const std::vector<double>& observed,
                               py::object simulation_failed,
                               FirstPythonError& first_error)
    : function_(std::move(function)),
      batch_(batch),
      named_(!components.empty()),
      m_(observed.size()),
      observed_(static_cast<py::ssize_t>(observed.size()), observed.data()),
      simulation_failed_(std::move(simulation_failed)),
      first_error_(first_error) {
  if (components.empty()) components.emplace_back("distance");
  for (std::string& name : components) {
    components_.push_back({std::move(name), ComponentKind::kThreshold, 1.0});
  }
  // One array for every call: read-only, so that a distance cannot change the data it is given.
  observed_.attr("setflags")(py::arg("write") = false);
}

void PythonDistance::Evaluate(std::span<const double> simulated, std::span<double> out) const {
  std::uint8_t status = 0;
  std::vector<char> reason(kFailureReasonBytes, '\0');
  BatchFailures failures{std::span(&status, 1), std::span(reason)};
  EvaluateBatch(simulated, out, failures);
  if (failures.failed(0)) throw SimulationFailed(std::string(failures.reason(0)));
}

void PythonDistance::EvaluateBatch(std::span<const double> simulated,
                                   std::span<double> out,
                                   BatchFailures& failures) const {
  const std::size_t n = failures.size();
  const std::size_t k = components_.size();
  COMBABC_CHECK(simulated.size() == n * m_ && out.size() == n * k);
  std::vector<std::size_t> measured;  // the candidates the function sees, in index order
  for (std::size_t i = 0; i < n; ++i) {
    if (!failures.failed(i)) measured.push_back(i);
  }
  if (measured.empty()) return;  // no hand-over of the GIL for nothing
  const auto km = static_cast<py::ssize_t>(k);
  const py::gil_scoped_acquire gil;
  first_error_.ThrowIfKept();
  try {
    if (batch_) {
      const auto count = static_cast<py::ssize_t>(measured.size());
      py::array_t<double> outputs({count, static_cast<py::ssize_t>(m_)});
      double* to = outputs.mutable_data();
      for (const std::size_t i : measured) {
        to = std::copy_n(simulated.begin() + static_cast<std::ptrdiff_t>(i * m_), m_, to);
      }
      Doubles values;
      try {
        values = Checked(function_(outputs, observed_),
                         named_ ? std::vector<py::ssize_t>{count, km} : std::vector{count},
                         "distance");
      } catch (py::error_already_set& e) {
        if (!e.matches(simulation_failed_)) throw;
        // SimulationFailed from a batch call: every candidate of the call failed.
        const std::string reason = py::str(e.value());
        for (const std::size_t i : measured) failures.Fail(i, reason);
        return;
      }
      for (std::size_t r = 0; r < measured.size(); ++r) {
        std::copy_n(
            values.data() + r * k, k, out.begin() + static_cast<std::ptrdiff_t>(measured[r] * k));
      }
      return;
    }
    for (const std::size_t i : measured) {
      const py::array_t<double> output(static_cast<py::ssize_t>(m_), simulated.data() + i * m_);
      try {
        const Doubles values = Checked(function_(output, observed_),
                                       named_ ? std::vector{km} : std::vector<py::ssize_t>{},
                                       "distance");
        std::copy_n(values.data(), k, out.begin() + static_cast<std::ptrdiff_t>(i * k));
      } catch (py::error_already_set& e) {
        if (!e.matches(simulation_failed_)) throw;
        failures.Fail(i, std::string(py::str(e.value())));
      }
    }
  } catch (py::error_already_set& e) {
    first_error_.Keep(e, "distance");
  }
}

}  // namespace combabc::python
