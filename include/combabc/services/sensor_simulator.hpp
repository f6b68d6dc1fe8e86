#pragma once
// The built-in plate model of the sensor as an engine Simulator: bits are the 36 clamps
// (1 = fixed), the output is |w| along the centreline at the model's output positions.
#include <memory>

#include "combabc/plate/sensor_model.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::services {

class SensorSimulator : public Simulator {
 public:
  explicit SensorSimulator(const plate::SensorOptions& options);
  int output_size() const override { return model_.num_outputs(); }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out) const override;
  const plate::SensorModel& model() const { return model_; }

 private:
  plate::SensorModel model_;
};

}  // namespace combabc::services
