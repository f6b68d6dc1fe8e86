#pragma once
// The random numbers a Python simulator asks for with rng=True (docs/python.md). Each candidate's
// come from its own RandomStream, two words drawn from it (CandidateSeed) keying them, so that what
// a candidate draws does not depend on the thread, the batch it was simulated in or a resume. A
// per-sample simulator gets a numpy Generator; a batched one a BatchRandom, one object for the
// batch whose draws are vectorised across the candidates (row i is candidate i's).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "combabc/rng/random_stream.hpp"

namespace combabc::python {

// Two words drawn from a candidate's stream: a numpy SeedSequence of 128 bits (distinct candidates
// never share a generator) and the key of its row in a BatchRandom.
struct CandidateSeed {
  std::uint64_t a = 0;
  std::uint64_t b = 0;
};
CandidateSeed DrawSeed(RandomStream& rng);

// numpy.random.default_rng((a, b)); default_rng is numpy.random.default_rng, looked up once by the
// caller. GIL held.
pybind11::object NumpyGenerator(const pybind11::object& default_rng, const CandidateSeed& seed);

// One per call of a batched simulator. Each method returns an array of shape (n, *size) (size
// None: (n,)) whose row i is drawn from candidate i's stream, RandomStream(a, b, 0) of its seed, in
// the order of the calls, so row i is the same for any batch that holds candidate i. Indexing and
// iterating give the candidates' numpy Generators (those a per-sample simulator gets), made when
// first asked for. GIL held throughout.
class BatchRandom {
 public:
  BatchRandom(std::span<RandomStream> candidates, pybind11::object default_rng);
  std::size_t size() const { return seeds_.size(); }
  // Uniform on [0, 1).
  pybind11::array_t<double> Random(const pybind11::object& size);
  // low + (high - low) U, normal loc + scale Z: numbers or arrays that broadcast against the
  // result.
  pybind11::object Uniform(const pybind11::object& low,
                           const pybind11::object& high,
                           const pybind11::object& size);
  pybind11::object Normal(const pybind11::object& loc,
                          const pybind11::object& scale,
                          const pybind11::object& size);
  pybind11::array_t<double> StandardNormal(const pybind11::object& size);
  // Uniform integers in [low, high) (high None: [0, low)), as numpy's Generator.integers.
  pybind11::array_t<std::int64_t> Integers(std::int64_t low,
                                           std::optional<std::int64_t> high,
                                           const pybind11::object& size);
  // Candidate i's numpy Generator (negative i from the end); IndexError out of range.
  pybind11::object Generator(std::int64_t i);

 private:
  // (n, *size) and the count per row.
  std::vector<pybind11::ssize_t> Shape(const pybind11::object& size, std::size_t& per_row) const;

  std::vector<CandidateSeed> seeds_;
  std::vector<RandomStream> streams_;
  std::vector<pybind11::object> generators_;  // None until asked for
  pybind11::object default_rng_;
};

// Adds the class BatchRandom to `m` (combabc._core; the benchmark's embedded module).
void BindBatchRandom(pybind11::module_& m);

}  // namespace combabc::python
