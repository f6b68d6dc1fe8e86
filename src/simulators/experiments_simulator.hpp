#pragma once
// Several simulators run one after the other on the same candidate, their outputs concatenated:
// an external simulator's experiments, each an instance told which experiment it simulates.
// A candidate fails if any experiment's simulation fails. It combines simulators through the
// Simulator interface only, so it sits with them; private to src (the simulator factory in
// src/services/adapters builds it).
#include <memory>
#include <vector>

#include "combabc/samplers/simulator.hpp"

namespace combabc {

class ExperimentsSimulator : public Simulator {
 public:
  explicit ExperimentsSimulator(std::vector<std::unique_ptr<Simulator>> parts);
  int output_size() const override { return output_size_; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;

 private:
  std::vector<std::unique_ptr<Simulator>> parts_;
  int output_size_ = 0;
};

}  // namespace combabc
