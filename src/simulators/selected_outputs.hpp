#pragma once
// A multi-fidelity run's cheap simulator as the sampler sees it: its outputs picked so that they
// stand for the expensive simulator's, one for one (LowFidelityConfig::output_map); the cheap
// simulator's other outputs are dropped. Private to src (the simulator factory in
// src/services/adapters builds it).
#include <memory>
#include <span>
#include <vector>

#include "combabc/samplers/simulator.hpp"

namespace combabc {

class SelectedOutputs : public Simulator {
 public:
  // picks[k]: the inner simulator's output that becomes output k.
  SelectedOutputs(std::unique_ptr<Simulator> inner, std::vector<int> picks);
  int output_size() const override { return static_cast<int>(picks_.size()); }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;

 private:
  std::unique_ptr<Simulator> inner_;
  std::vector<int> picks_;
};

}  // namespace combabc
