#pragma once
// The built-in plate model of the sensor as an engine Simulator: bits are the clamps (1 = fixed),
// reals the continuous unknowns named at construction (foundation_stiffness, stiffness_scale,
// loss_factor: plate::SensorVariation), the output is |w| along each experiment's scan line at
// its output positions, experiment after experiment. The experiments that share a frequency are
// one model's load cases, solved with one factorization per configuration.
#include <memory>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::services {

class SensorSimulator : public Simulator {
 public:
  // plans: SensorModels(config), each model's load cases being the experiments it lists (their
  // outputs in experiment order make the simulator's output). real_names: the ParameterSpace's
  // reals, in order; each must name a SensorVariation field (throws combabc::Error(kConfig)).
  // precompute: how the models build their pieces (threads, the disk cache; bit-neutral).
  explicit SensorSimulator(const std::vector<SensorModelPlan>& plans,
                           std::vector<std::string> real_names = {},
                           const plate::PrecomputeOptions& precompute = {});
  int output_size() const override { return output_size_; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;
  int num_clamps() const { return models_.front().model->num_clamps(); }
  // The models, one per frequency (SensorModels' order).
  std::size_t num_models() const { return models_.size(); }
  const plate::SensorModel& model(std::size_t m = 0) const { return *models_.at(m).model; }

 private:
  struct Model {
    std::unique_ptr<plate::SensorModel> model;
    // Where each of its outputs goes in the simulator's output; empty when they are the whole
    // output in order (one model holding every experiment), the common case.
    std::vector<std::size_t> scatter;
  };
  plate::SensorVariation Variation(std::span<const double> reals) const;
  // One candidate through every model; throws plate::SingularSystem.
  void Profile(std::span<const std::uint8_t> bits,
               const plate::SensorVariation* variation,
               std::span<double> out) const;

  std::vector<Model> models_;
  int output_size_ = 0;
  std::vector<std::string> real_names_;
  // The SensorVariation field each real sets, by its name (plate::kSensorVariationFields).
  std::vector<std::optional<double> plate::SensorVariation::*> members_;
};

}  // namespace combabc::services
