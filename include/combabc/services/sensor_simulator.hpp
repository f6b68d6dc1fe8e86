#pragma once
// The built-in plate model of the sensor as an engine Simulator: bits are the 36 clamps
// (1 = fixed), reals the continuous unknowns named at construction (foundation_stiffness,
// stiffness_scale, loss_factor: plate::SensorVariation), the output is |w| along the centreline
// at the model's output positions.
#include <memory>
#include <string>
#include <vector>

#include "combabc/plate/sensor_model.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::services {

class SensorSimulator : public Simulator {
 public:
  // real_names: the ParameterSpace's reals, in order; each must name a SensorVariation field
  // (throws combabc::Error(kConfig) otherwise).
  explicit SensorSimulator(const plate::SensorOptions& options,
                           std::vector<std::string> real_names = {});
  int output_size() const override { return model_.num_outputs(); }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;
  const plate::SensorModel& model() const { return model_; }

 private:
  plate::SensorVariation Variation(std::span<const double> reals) const;

  plate::SensorModel model_;
  std::vector<std::string> real_names_;
  // The SensorVariation field each real sets, by its name (plate::kSensorVariationFields).
  std::vector<std::optional<double> plate::SensorVariation::*> members_;
};

}  // namespace combabc::services
