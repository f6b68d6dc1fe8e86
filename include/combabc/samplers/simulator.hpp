#pragma once
// The simulator f_theta: from a parameter value (bits + reals) to an output vector Y*.
#include <span>
#include <stdexcept>
#include <string>

#include "combabc/core/batch_failures.hpp"
#include "combabc/core/error.hpp"
#include "combabc/params/parameter_value.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

// Thrown by a simulator for one candidate whose simulation failed in a way a run can survive (an
// external process that crashed, hung, or printed something unreadable): the candidate counts as
// a failed simulation, with `what()` as its reason, and is never accepted. Any other exception is
// a defect or a fatal condition and ends the run.
class SimulationFailed : public std::runtime_error {
 public:
  // `kind`: what a single simulation outside a run (`combabc simulate`) reports it as: a crash
  // by default, a config error for a configuration the model cannot solve.
  explicit SimulationFailed(const std::string& reason, ErrorKind kind = ErrorKind::kSoftware)
      : std::runtime_error(reason), kind_(kind) {}
  ErrorKind kind() const { return kind_; }

 private:
  ErrorKind kind_;
};

class Simulator {
 public:
  virtual ~Simulator() = default;
  virtual int output_size() const = 0;
  // theta: the full bit vector and the reals of the run's ParameterSpace. rng: the candidate's
  // own stream, for stochastic simulators (deterministic ones ignore it). Must be thread-safe.
  // Throwing SimulationFailed makes this candidate a failed simulation (never accepted, counted
  // and recorded with its reason); any other exception ends the run naming the candidate.
  virtual void Simulate(const ParameterView& theta,
                        RandomStream& rng,
                        std::span<double> out) const = 0;
  // Batch form for simulators that vectorise: out row-major (batch.count x output_size()),
  // rngs[i] for candidate i; failures.Fail(i, reason) marks candidate i failed (its outputs are
  // then ignored). The default loops over Simulate and turns a SimulationFailed into Fail, so one
  // failed candidate does not fail the batch. Any other exception ends the run.
  virtual void SimulateBatch(const ParameterBatch& batch,
                             std::span<RandomStream> rngs,
                             std::span<double> out,
                             BatchFailures& failures) const;
};

}  // namespace combabc
