#pragma once
// The simulator f_theta: from a parameter value (bits + reals) to an output vector Y*.
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "combabc/params/parameter_value.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

// Thrown by a simulator for one candidate whose simulation failed in a way a run can survive (an
// external process that crashed, hung, or printed something unreadable): the candidate counts as
// a failed simulation, with `what()` as its reason, and is never accepted. Any other exception is
// a defect or a fatal condition and ends the run.
class SimulationFailed : public std::runtime_error {
 public:
  explicit SimulationFailed(const std::string& reason) : std::runtime_error(reason) {}
};

class Simulator {
 public:
  virtual ~Simulator() = default;
  virtual int output_size() const = 0;
  // theta: the full bit vector and the reals of the run's ParameterSpace. rng: the candidate's
  // own stream, for stochastic simulators (deterministic ones ignore it). Must be thread-safe.
  // Throwing marks the run failed with the candidate named.
  virtual void Simulate(const ParameterView& theta,
                        RandomStream& rng,
                        std::span<double> out) const = 0;
  // Batch form for simulators that vectorise: out row-major (batch.count x output_size()),
  // rngs[i] for candidate i. The default loops over Simulate.
  virtual void SimulateBatch(const ParameterBatch& batch,
                             std::span<RandomStream> rngs,
                             std::span<double> out) const;
};

}  // namespace combabc
