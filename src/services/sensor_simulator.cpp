#include "combabc/services/sensor_simulator.hpp"

namespace combabc::services {

SensorSimulator::SensorSimulator(const plate::SensorOptions& options) : model_(options) {}

void SensorSimulator::Simulate(std::span<const std::uint8_t> bits,
                               RandomStream& /*rng*/,
                               std::span<double> out) const {
  model_.Profile(bits, out);
}

void SensorSimulator::SimulateBatch(std::span<const std::uint8_t> bits,
                                    std::span<RandomStream> rngs,
                                    std::span<double> out) const {
  // One thread here: the engine already runs one batch per worker thread.
  model_.ProfileBatch(bits, rngs.size(), out, 1);
}

}  // namespace combabc::services
