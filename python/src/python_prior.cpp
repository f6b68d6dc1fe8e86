#include "python_prior.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "batch_random.hpp"
#include "combabc/core/error.hpp"
#include "combabc/params/joint_prior.hpp"
#include "python_call.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

// The two callables, numpy's default_rng and the first exception they raised. The prior may be
// dropped on a thread without the GIL (the run's workers hold copies), so the Python references
// are released with it held.
struct Callables {
  py::object log_density, sample, default_rng;
  FirstPythonError error;
};
using SharedCallables = std::shared_ptr<Callables>;

SharedCallables Hold(py::object log_density, py::object sample) {
  py::object default_rng = py::module_::import("numpy.random").attr("default_rng");
  // NOLINTNEXTLINE(cppcoreguidelines-owning-memory): owned by the shared_ptr returned
  auto* c = new Callables;
  c->log_density = std::move(log_density);
  c->sample = std::move(sample);
  c->default_rng = std::move(default_rng);
  return {c, [](Callables* p) {
            const py::gil_scoped_acquire gil;
            delete p;  // NOLINT(cppcoreguidelines-owning-memory): the deleter of a shared_ptr
          }};
}

// A Python exception or a bad result as the one-line combabc::Error(kConfig) a run reports.
[[noreturn]] void Fail(const std::string& what) {
  throw Error(ErrorKind::kConfig, "CustomPrior: " + what);
}

// The object the user gave, or TypeError naming the argument.
py::object Callable(const py::object& f, const char* name) {
  if (!PyCallable_Check(f.ptr())) {
    throw py::type_error(std::string("CustomPrior: ") + name + " must be callable, not " +
                         Py_TYPE(f.ptr())->tp_name);
  }
  return f;
}

// A prior from two Python callables. The sampler gets a numpy Generator seeded from the
// candidate's stream (DrawSeed), as a per-sample simulator's rng=, so that a draw does not depend
// on the thread. Both take the GIL: the engine calls them from its workers.
std::shared_ptr<const JointPrior> MakePythonPrior(const SharedCallables& c, int dimension) {
  if (dimension < 1) {
    throw py::value_error("CustomPrior: dimension = " + std::to_string(dimension) +
                          "; must be >= 1");
  }
  const auto d = static_cast<py::ssize_t>(dimension);
  return MakeCustomPrior(
      dimension,
      [c, d](std::span<const double> x) {
        const py::gil_scoped_acquire gil;
        py::object result;
        try {
          const py::array_t<double> point(d, x.data());
          result = c->log_density(point);
        } catch (py::error_already_set& e) {
          Fail("log_density raised " + c->error.Remember(e, "prior's log_density"));
        }
        try {
          return *Checked(result, {}, "log density").data();
        } catch (py::error_already_set& e) {
          Fail(c->error.Remember(e, "prior's log_density"));
        }
      },
      [c, d](RandomStream& rng, std::span<double> x) {
        const py::gil_scoped_acquire gil;
        py::object result;
        try {
          result = c->sample(NumpyGenerator(c->default_rng, DrawSeed(rng)));
        } catch (py::error_already_set& e) {
          Fail("sample raised " + c->error.Remember(e, "prior's sample"));
        }
        try {
          // A number for a prior of one real, or an array of shape (dimension,). Anything else
          // (a string, a dict, a complex number, an object) is Checked's TypeError.
          const py::array any = py::array::ensure(result);  // null if numpy cannot hold it
          const bool number = d == 1 && any && any.ndim() == 0;
          const Doubles values = Checked(
              result, number ? std::vector<py::ssize_t>{} : std::vector<py::ssize_t>{d}, "sampler");
          std::copy(values.data(), values.data() + d, x.begin());
        } catch (py::error_already_set& e) {
          Fail(c->error.Remember(e, "prior's sample"));
        }
      });
}

class PythonCustomPrior : public PythonJointPrior {
 public:
  PythonCustomPrior(const py::object& log_density, const py::object& sample, int dimension)
      : PythonCustomPrior(Hold(Callable(log_density, "log_density"), Callable(sample, "sample")),
                          dimension) {}

 private:
  PythonCustomPrior(const SharedCallables& c, int dimension)
      : PythonJointPrior(MakePythonPrior(c, dimension),
                         "CustomPrior(dimension=" + std::to_string(dimension) + ")",
                         std::shared_ptr<FirstPythonError>(c, &c->error)) {}
};

std::string ListRepr(const std::vector<double>& values) {
  return py::repr(py::cast(values)).cast<std::string>();
}

// MultivariateNormalPrior(mean=[0.0, 0.0], covariance=[[1.0, 0.5], [0.5, 1.0]]).
std::string NormalRepr(const std::vector<double>& mean, const std::vector<double>& covariance) {
  std::string rows;
  for (std::size_t i = 0; i < mean.size(); ++i) {
    const auto row = covariance.begin() + static_cast<std::ptrdiff_t>(i * mean.size());
    rows += (i ? ", " : "") +
            ListRepr(std::vector<double>(row, row + static_cast<std::ptrdiff_t>(mean.size())));
  }
  return "MultivariateNormalPrior(mean=" + ListRepr(mean) + ", covariance=[" + rows + "])";
}

class PythonNormalPrior : public PythonJointPrior {
 public:
  PythonNormalPrior(const std::vector<double>& mean, const std::vector<double>& covariance)
      : PythonJointPrior(MakeMultivariateNormalPrior(mean, covariance),
                         NormalRepr(mean, covariance)) {}
};

// The covariance as a d x d nested list or array, flattened row-major; ValueError for another
// shape.
std::vector<double> Covariance(const py::object& value, std::size_t d) {
  const Doubles matrix = Doubles::ensure(value);
  const auto n = static_cast<py::ssize_t>(d);
  if (!matrix || matrix.ndim() != 2 || matrix.shape(0) != n || matrix.shape(1) != n) {
    throw py::value_error("MultivariateNormalPrior: covariance must be a " + std::to_string(d) +
                          " x " + std::to_string(d) + " matrix (one row per entry of mean)");
  }
  std::vector<double> flat;
  for (py::ssize_t i = 0; i < n; ++i) {
    for (py::ssize_t j = 0; j < n; ++j) flat.push_back(matrix.at(i, j));
  }
  return flat;
}

// CheckJointPrior on the reals `names` with bounds low / high (default unbounded): what a run's
// space checks before any simulation, as one line.
void Check(const PythonJointPrior& p,
           const std::vector<std::string>& names,
           std::vector<double> low,
           std::vector<double> high) {
  const auto d = static_cast<std::size_t>(p.dimension());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (low.empty()) low.assign(d, -kInf);
  if (high.empty()) high.assign(d, kInf);
  if (names.size() != d || low.size() != d || high.size() != d) {
    throw py::value_error("check: names, low and high need " + std::to_string(d) +
                          " entries each (the prior's dimension)");
  }
  CheckJointPrior(*RestrictJointPrior(p.prior(), names, low, high), names, low, high);
}

}  // namespace

void RegisterPriors(py::module_& m) {
  py::class_<PythonJointPrior>(m, "JointPrior")
      .def_property_readonly("dimension", &PythonJointPrior::dimension)
      .def("check",
           &Check,
           py::arg("names"),
           py::arg("low") = std::vector<double>{},
           py::arg("high") = std::vector<double>{})
      .def("log_density",
           [](const PythonJointPrior& p, const std::vector<double>& x) {
             if (x.size() != static_cast<std::size_t>(p.dimension())) {
               throw py::value_error("log_density: x needs " + std::to_string(p.dimension()) +
                                     " values");
             }
             return p.prior()->LogDensity(x);
           })
      .def("__repr__", &PythonJointPrior::repr);
  py::class_<PythonCustomPrior, PythonJointPrior>(m, "CustomPrior")
      .def(py::init<const py::object&, const py::object&, int>(),
           py::kw_only(),
           py::arg("log_density"),
           py::arg("sample"),
           py::arg("dimension") = 1);
  py::class_<PythonNormalPrior, PythonJointPrior>(m, "MultivariateNormalPrior")
      .def(py::init([](const std::vector<double>& mean, const py::object& covariance) {
             return PythonNormalPrior(mean, Covariance(covariance, mean.size()));
           }),
           py::arg("mean"),
           py::arg("covariance"));
}

}  // namespace combabc::python
