#include "python_call.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace py = pybind11;

namespace combabc::python {
namespace {

std::string Shape(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) {
    text += (k ? ", " : "") + std::to_string(a.shape(k));
  }
  return text + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

Doubles Checked(const py::object& result,
                const std::vector<py::ssize_t>& expected,
                const char* who) {
  // numpy's forced cast would turn a complex number into its real part and a string of digits
  // into a number: refuse those kinds rather than compute with a value the function never meant.
  const py::array raw = py::array::ensure(result);
  const char kind = raw ? raw.dtype().kind() : 'O';
  if (kind == 'U' || kind == 'S') {
    PyErr_Format(PyExc_TypeError,
                 "the %s returned %s, not an array of numbers",
                 who,
                 Py_TYPE(result.ptr())->tp_name);
    throw py::error_already_set();
  }
  if (kind == 'c' || kind == 'V' || kind == 'M' || kind == 'm') {
    PyErr_Format(PyExc_TypeError,
                 "the %s returned %s of dtype %s, not an array of real numbers",
                 who,
                 Py_TYPE(result.ptr())->tp_name,
                 py::str(raw.dtype()).cast<std::string>().c_str());
    throw py::error_already_set();
  }
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

void FirstPythonError::Keep(py::error_already_set& error, const char* who) {
  const std::string text = Remember(error, who);
  throw std::runtime_error(std::string("the Python ") + who + " raised " + text);
}

std::string FirstPythonError::Remember(py::error_already_set& error, const char* who) {
  std::string text = py::str(error.type().attr("__name__"));
  text += ": " + std::string(py::str(error.value()));
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!error_) {
    error_ = error;
    who_ = who;
  }
  return text;
}

void FirstPythonError::Clear() {
  const std::lock_guard<std::mutex> lock(mutex_);
  error_.reset();
  who_.clear();
}

void FirstPythonError::ThrowIfKept() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (error_) throw std::runtime_error("the Python " + who_ + " raised earlier");
}

std::optional<py::error_already_set> FirstPythonError::error() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

}  // namespace combabc::python
