#include "combabc/metrics/joint_distance.hpp"

#include <stdexcept>

namespace combabc {

JointDistance::JointDistance(std::vector<Part> parts) : parts_(std::move(parts)) {
  if (parts_.empty()) throw std::invalid_argument("JointDistance: no experiments");
  std::size_t components = 0;
  for (const Part& p : parts_) {
    if (!p.distance || p.output_offset != output_size_) {
      throw std::invalid_argument("JointDistance: parts must cover the outputs in order");
    }
    output_size_ += p.distance->output_size();
    component_offsets_.push_back(components);
    components += p.distance->configs().size();
  }
  component_offsets_.push_back(components);
}

std::vector<DistanceComponent> JointDistance::components() const {
  std::vector<DistanceComponent> all;
  for (const Part& p : parts_) {
    for (DistanceComponent c : p.distance->components()) {
      if (!p.name.empty()) c.name = p.name + "/" + c.name;
      all.push_back(std::move(c));
    }
  }
  return all;
}

void JointDistance::Evaluate(std::span<const double> simulated, std::span<double> out) const {
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    const Part& p = parts_[i];
    p.distance->Evaluate(
        simulated.subspan(p.output_offset, p.distance->output_size()),
        out.subspan(component_offsets_[i], component_offsets_[i + 1] - component_offsets_[i]));
  }
}

std::vector<ThresholdSchedule> JointDistance::threshold_schedules() const {
  std::vector<ThresholdSchedule> all;
  for (const Part& p : parts_) {
    for (ThresholdSchedule& s : p.distance->threshold_schedules()) all.push_back(std::move(s));
  }
  return all;
}

}  // namespace combabc
