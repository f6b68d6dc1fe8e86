#pragma once
// The distance of several experiments (docs/algorithm.md, "Several experiments"): each experiment
// compares its own slice of the simulator's output (its outputs) with its own measured data, and
// the distance vector is the experiments' components one after the other. A candidate is accepted
// when every component passes (each keeps its own schedule), so the ABC posterior is that of the
// product of the experiments' acceptance: the experiments are independent given the bits.
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/metrics/composite_distance.hpp"

namespace combabc {

class JointDistance : public Distance {
 public:
  struct Part {
    std::string name;  // "" for a single unnamed experiment: its components keep their names
    std::size_t output_offset = 0;
    std::unique_ptr<CompositeDistance> distance;  // over distance->output_size() outputs
  };
  // Parts in output order, contiguous from output 0 (throws std::invalid_argument otherwise).
  explicit JointDistance(std::vector<Part> parts);

  // Each part's components, named "<experiment>/<component>" for a named experiment.
  std::vector<DistanceComponent> components() const override;
  // simulated: every part's outputs (output_size()).
  void Evaluate(std::span<const double> simulated, std::span<double> out) const override;

  // One schedule per threshold or likelihood component, part after part (SmcOptions::thresholds).
  std::vector<ThresholdSchedule> threshold_schedules() const;
  std::size_t output_size() const { return output_size_; }
  const std::vector<Part>& parts() const { return parts_; }
  // The first component of part p in the distance vector.
  std::size_t component_offset(std::size_t p) const { return component_offsets_.at(p); }

 private:
  std::vector<Part> parts_;
  std::vector<std::size_t> component_offsets_;  // one per part, then the total
  std::size_t output_size_ = 0;
};

}  // namespace combabc
