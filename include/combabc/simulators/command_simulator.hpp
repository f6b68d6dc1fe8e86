#pragma once
// A program run once per candidate (docs/simulators.md, "Command simulator"): the parameters in a
// file or on stdin, the outputs read from stdout or a file, in a fresh working directory inside
// the run's folder that is removed afterwards. A call that crashes, times out (the whole process
// group is killed), or hands back something unreadable, the wrong number of values or NaN is
// retried `retries` times and then throws SimulationFailed with the reason. Thread-safe.
#include <atomic>
#include <span>

#include "combabc/samplers/simulator.hpp"
#include "combabc/simulators/external_simulator.hpp"
#include "combabc/simulators/work_directory.hpp"

namespace combabc {

class CommandSimulator : public Simulator {
 public:
  // Throws combabc::Error(kConfig) for options that fail IsValid.
  explicit CommandSimulator(ExternalSimulatorOptions options);
  int output_size() const override { return options_.output_size; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;

 private:
  const SimulatorExperiment* Experiment() const {
    return options_.experiment ? &*options_.experiment : nullptr;
  }
  // One attempt; returns the failure reason, empty on success.
  std::string Attempt(const ParameterView& theta, std::span<double> out) const;

  ExternalSimulatorOptions options_;
  WorkDirectory work_;
};

}  // namespace combabc
