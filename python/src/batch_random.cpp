#include "batch_random.hpp"

#include <pybind11/stl.h>

#include <limits>
#include <string>
#include <utility>

namespace py = pybind11;

namespace combabc::python {
namespace {

// A number given as a number (Python's, NumPy's scalar, a 0-d array), or nothing for an array or a
// sequence, which numpy broadcasts against the result.
std::optional<double> Scalar(const py::object& value, const char* what) {
  if (py::isinstance<py::array>(value) && value.cast<py::array>().ndim() > 0) return std::nullopt;
  if (py::isinstance<py::sequence>(value) && !py::isinstance<py::str>(value)) return std::nullopt;
  try {
    return value.cast<double>();
  } catch (const py::cast_error&) {
    throw py::type_error(std::string(what) + " must be a number or an array of numbers, not " +
                         std::string(py::str(py::type::of(value).attr("__name__"))));
  }
}

// Uniform on [0, range) without modulo bias: rejects the low 2^64 mod range values.
std::uint64_t Below(RandomStream& rng, std::uint64_t range) {
  const std::uint64_t reject = (std::numeric_limits<std::uint64_t>::max() - range + 1) % range;
  for (;;) {
    const std::uint64_t x = rng.Next();
    if (x >= reject) return x % range;
  }
}

}  // namespace

CandidateSeed DrawSeed(RandomStream& rng) {
  CandidateSeed seed;
  seed.a = rng.Next();
  seed.b = rng.Next();
  return seed;
}

py::object NumpyGenerator(const py::object& default_rng, const CandidateSeed& seed) {
  return default_rng(py::make_tuple(seed.a, seed.b));
}

BatchRandom::BatchRandom(std::span<RandomStream> candidates, py::object default_rng)
    : default_rng_(std::move(default_rng)) {
  seeds_.reserve(candidates.size());
  streams_.reserve(candidates.size());
  for (RandomStream& rng : candidates) {
    const CandidateSeed seed = DrawSeed(rng);
    seeds_.push_back(seed);
    streams_.emplace_back(seed.a, seed.b, 0);
  }
  generators_.resize(candidates.size());
}

std::vector<py::ssize_t> BatchRandom::Shape(const py::object& size, std::size_t& per_row) const {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(seeds_.size())};
  std::vector<py::ssize_t> tail;
  // An int (Python's, NumPy's, a 0-d array) or a sequence of them (a tuple, a 1-d array).
  const bool one = py::isinstance<py::array>(size) ? size.cast<py::array>().ndim() == 0
                                                   : PyIndex_Check(size.ptr()) != 0;
  try {
    if (size.is_none()) {
      // one draw per candidate
    } else if (one) {
      tail.push_back(size.cast<py::ssize_t>());
    } else {
      for (const py::handle& k : size.cast<py::sequence>()) tail.push_back(k.cast<py::ssize_t>());
    }
  } catch (const py::builtin_exception&) {  // cast_error, type_error
    throw py::type_error("size: None, an int or a tuple of ints, not " +
                         std::string(py::str(py::type::of(size).attr("__name__"))));
  }
  per_row = 1;
  for (const py::ssize_t k : tail) {
    if (k < 0) throw py::value_error("size: negative dimensions are not allowed");
    per_row *= static_cast<std::size_t>(k);
    shape.push_back(k);
  }
  return shape;
}

py::array_t<double> BatchRandom::Random(const py::object& size) {
  std::size_t k = 0;
  py::array_t<double> out(Shape(size, k));
  double* values = out.mutable_data();
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    for (std::size_t j = 0; j < k; ++j) values[i * k + j] = streams_[i].Uniform();
  }
  return out;
}

py::array_t<double> BatchRandom::StandardNormal(const py::object& size) {
  std::size_t k = 0;
  py::array_t<double> out(Shape(size, k));
  double* values = out.mutable_data();
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    for (std::size_t j = 0; j < k; ++j) values[i * k + j] = streams_[i].Normal();
  }
  return out;
}

py::object BatchRandom::Uniform(const py::object& low,
                                const py::object& high,
                                const py::object& size) {
  const std::optional<double> a = Scalar(low, "uniform: low");
  const std::optional<double> b = Scalar(high, "uniform: high");
  py::array_t<double> u = Random(size);
  if (!a || !b) return low + (high - low) * u;  // numpy broadcasts
  double* values = u.mutable_data();
  for (py::ssize_t i = 0; i < u.size(); ++i) values[i] = *a + (*b - *a) * values[i];
  return u;
}

py::object BatchRandom::Normal(const py::object& loc,
                               const py::object& scale,
                               const py::object& size) {
  const std::optional<double> mean = Scalar(loc, "normal: loc");
  const std::optional<double> sd = Scalar(scale, "normal: scale");
  if (sd && *sd < 0.0) throw py::value_error("normal: scale < 0");
  py::array_t<double> z = StandardNormal(size);
  if (!mean || !sd) return loc + scale * z;  // numpy broadcasts
  double* values = z.mutable_data();
  for (py::ssize_t i = 0; i < z.size(); ++i) values[i] = *mean + *sd * values[i];
  return z;
}

py::array_t<std::int64_t> BatchRandom::Integers(std::int64_t low,
                                                std::optional<std::int64_t> high,
                                                const py::object& size) {
  if (!high) {
    high = low;
    low = 0;
  }
  if (low >= *high) throw py::value_error("integers: low >= high");
  const std::uint64_t range = static_cast<std::uint64_t>(*high) - static_cast<std::uint64_t>(low);
  std::size_t k = 0;
  py::array_t<std::int64_t> out(Shape(size, k));
  std::int64_t* values = out.mutable_data();
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    for (std::size_t j = 0; j < k; ++j) {
      values[i * k + j] =
          static_cast<std::int64_t>(static_cast<std::uint64_t>(low) + Below(streams_[i], range));
    }
  }
  return out;
}

py::object BatchRandom::Generator(std::int64_t i) {
  const auto n = static_cast<std::int64_t>(seeds_.size());
  if (i < 0) i += n;
  if (i < 0 || i >= n) throw py::index_error("BatchRandom index out of range");
  const auto k = static_cast<std::size_t>(i);
  if (!generators_[k]) generators_[k] = NumpyGenerator(default_rng_, seeds_[k]);
  return generators_[k];
}

void BindBatchRandom(py::module_& m) {
  py::class_<BatchRandom>(m, "BatchRandom")
      .def("random", &BatchRandom::Random, py::arg("size") = py::none())
      .def("uniform",
           &BatchRandom::Uniform,
           py::arg("low") = 0.0,
           py::arg("high") = 1.0,
           py::arg("size") = py::none())
      .def("normal",
           &BatchRandom::Normal,
           py::arg("loc") = 0.0,
           py::arg("scale") = 1.0,
           py::arg("size") = py::none())
      .def("standard_normal", &BatchRandom::StandardNormal, py::arg("size") = py::none())
      .def("integers",
           &BatchRandom::Integers,
           py::arg("low"),
           py::arg("high") = py::none(),
           py::arg("size") = py::none())
      .def("__len__", &BatchRandom::size)
      .def("__getitem__", &BatchRandom::Generator)
      .def("__repr__", [](const BatchRandom& r) {
        return "<combabc.BatchRandom: " + std::to_string(r.size()) + " candidates>";
      });
}

}  // namespace combabc::python
