#include "combabc/services/sensor_simulator.hpp"

namespace combabc::services {

SensorSimulator::SensorSimulator(const plate::SensorOptions& options) : model_(options) {}

void SensorSimulator::Simulate(const ParameterView& theta,
                               RandomStream& /*rng*/,
                               std::span<double> out) const {
  model_.Profile(theta.bits, out);
}

void SensorSimulator::SimulateBatch(const ParameterBatch& batch,
                                    std::span<RandomStream> /*rngs*/,
                                    std::span<double> out) const {
  // One thread here: the engine already runs one batch per worker thread.
  model_.ProfileBatch(batch.bits, batch.count, out, 1);
}

}  // namespace combabc::services
