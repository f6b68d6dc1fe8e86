#include "python_prior.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/params/joint_prior.hpp"
#include "python_call.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

// The two callables and numpy's default_rng. The prior may be dropped on a thread without the
// GIL (the run's workers hold copies), so the Python references are released with it held.
struct Callables {
  py::object log_density, sample, default_rng;
};
using SharedCallables = std::shared_ptr<Callables>;

SharedCallables Hold(py::object log_density, py::object sample) {
  auto* c = new Callables{std::move(log_density),
                          std::move(sample),
                          py::module_::import("numpy.random").attr("default_rng")};
  return {c, [](Callables* p) {
            const py::gil_scoped_acquire gil;
            delete p;  // NOLINT(cppcoreguidelines-owning-memory): the deleter of a shared_ptr
          }};
}

// A Python exception or a bad result as the one-line combabc::Error(kConfig) a run reports.
[[noreturn]] void Fail(const std::string& what) {
  throw Error(ErrorKind::kConfig, "CustomPrior: " + what);
}

std::string Raised(py::error_already_set& e) {
  return std::string(py::str(e.type().attr("__name__"))) + ": " + std::string(py::str(e.value()));
}

// The object the user gave, or TypeError naming the argument.
py::object Callable(const py::object& f, const char* name) {
  if (!PyCallable_Check(f.ptr())) {
    throw py::type_error(std::string("CustomPrior: ") + name + " must be callable, not " +
                         Py_TYPE(f.ptr())->tp_name);
  }
  return f;
}

class PythonCustomPrior {
 public:
  PythonCustomPrior(const py::object& log_density, const py::object& sample, int dimension)
      : dimension_(dimension) {
    if (dimension < 1) {
      throw py::value_error("CustomPrior: dimension = " + std::to_string(dimension) +
                            "; must be >= 1");
    }
    SharedCallables c = Hold(Callable(log_density, "log_density"), Callable(sample, "sample"));
    const auto d = static_cast<py::ssize_t>(dimension);
    prior_ = MakeCustomPrior(
        dimension,
        [c, d](std::span<const double> x) {
          const py::gil_scoped_acquire gil;
          try {
            const py::array_t<double> point(d, x.data());
            const py::object result = c->log_density(point);
            const Doubles value = Checked(result, {}, "log density");
            return *value.data();
          } catch (py::error_already_set& e) {
            Fail("log_density raised " + Raised(e));
          }
        },
        [c, d](RandomStream& rng, std::span<double> x) {
          const py::gil_scoped_acquire gil;
          try {
            const std::uint64_t a = rng.Next(), b = rng.Next();
            const py::object result = c->sample(c->default_rng(py::make_tuple(a, b)));
            // A number for a prior of one real, or an array of shape (dimension,).
            const Doubles values =
                Checked(result,
                        d == 1 && Doubles::ensure(result).ndim() == 0 ? std::vector<py::ssize_t>{}
                                                                      : std::vector<py::ssize_t>{d},
                        "sampler");
            std::copy(values.data(), values.data() + d, x.begin());
          } catch (py::error_already_set& e) {
            Fail("sample raised " + Raised(e));
          }
        });
  }

  int dimension() const { return dimension_; }
  const std::shared_ptr<const JointPrior>& prior() const { return prior_; }

  // CheckJointPrior on the reals `names` with bounds low / high (default unbounded): what a run's
  // space checks before any simulation, as one line.
  void Check(const std::vector<std::string>& names,
             std::vector<double> low,
             std::vector<double> high) const {
    const auto d = static_cast<std::size_t>(dimension_);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    if (low.empty()) low.assign(d, -kInf);
    if (high.empty()) high.assign(d, kInf);
    if (names.size() != d || low.size() != d || high.size() != d) {
      throw py::value_error("CustomPrior.check: names, low and high need " + std::to_string(d) +
                            " entries each (the prior's dimension)");
    }
    CheckJointPrior(*prior_, names, low, high);
  }

 private:
  int dimension_;
  std::shared_ptr<const JointPrior> prior_;
};

}  // namespace

void RegisterPriors(py::module_& m) {
  py::class_<PythonCustomPrior>(m, "CustomPrior")
      .def(py::init<const py::object&, const py::object&, int>(),
           py::kw_only(),
           py::arg("log_density"),
           py::arg("sample"),
           py::arg("dimension") = 1)
      .def_property_readonly("dimension", &PythonCustomPrior::dimension)
      .def("check",
           &PythonCustomPrior::Check,
           py::arg("names"),
           py::arg("low") = std::vector<double>{},
           py::arg("high") = std::vector<double>{})
      .def("log_density",
           [](const PythonCustomPrior& p, const std::vector<double>& x) {
             if (x.size() != static_cast<std::size_t>(p.dimension())) {
               throw py::value_error("CustomPrior.log_density: x needs " +
                                     std::to_string(p.dimension()) + " values");
             }
             return p.prior()->LogDensity(x);
           })
      .def("__repr__", [](const PythonCustomPrior& p) {
        return "CustomPrior(dimension=" + std::to_string(p.dimension()) + ")";
      });
}

}  // namespace combabc::python
