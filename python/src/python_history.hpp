#pragma once
// The history file of a run whose simulator is written in Python (combabc.run(problem,
// output_directory=...); docs/python.md): what it records of the problem, and the fingerprint
// that combabc.resume(path, problem, options) checks, so that a resumed run is the run that
// started. The Python functions themselves cannot be fingerprinted: the caller passes the same
// ones again.
#include <string>
#include <utility>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/params/continuous_prior.hpp"
#include "combabc/samplers/smc_options.hpp"

namespace combabc::python {

// What a Python run is made of, as far as the history and its fingerprint see it.
struct PythonProblem {
  const BinarySpace* space = nullptr;
  const std::vector<ContinuousParameter>* reals = nullptr;
  const std::vector<double>* observed = nullptr;
  std::vector<DistanceComponent> components;
  bool batch = false;            // the simulator takes a batch
  bool rng = false;              // the simulator takes rng=
  bool python_distance = false;  // the distance is a Python function (else Euclidean)
  bool distance_batch = false;
  bool low_fidelity = false;  // a multi-fidelity run (a cheap simulator; options.multi_fidelity)
};

// The fingerprint part every Python run's history has, and no config run's: how a resume tells
// the two apart (`combabc resume` refuses it, combabc.resume(path) without a problem too).
inline constexpr const char* kPythonFingerprintPart = "python_problem";

// The run's metadata for HistoryStore::Create: no config text; the observed data by index (unit
// "index"), as the outputs; the options' seed, estimator, proposal and tempering form.
RunMetadata PythonRunMetadata(const PythonProblem& problem, const SmcOptions& options);

// (part, 16 hex digits) pairs over the problem (space, reals, data, distance components, how the
// simulator is called) and the options that decide what is sampled (not threads nor the stop
// limits, which a resume may change).
std::vector<std::pair<std::string, std::string>> PythonRunFingerprint(const PythonProblem& problem,
                                                                      const SmcOptions& options);

}  // namespace combabc::python
