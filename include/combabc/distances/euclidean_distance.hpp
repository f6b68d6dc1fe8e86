#pragma once
// The Euclidean distance ||Y* - Y||_2 between a simulated output and the observed data: one
// threshold component, "euclidean". The default distance of a problem whose simulator is written
// in Python (docs/python.md); a config run's distances are the paper's metrics (metrics/).
#include <span>
#include <vector>

#include "combabc/distances/distance.hpp"

namespace combabc {

class EuclideanDistance final : public Distance {
 public:
  // observed: the data Y; every simulated output has as many values.
  explicit EuclideanDistance(std::vector<double> observed);
  std::vector<DistanceComponent> components() const override;
  void Evaluate(std::span<const double> simulated, std::span<double> out) const override;

 private:
  std::vector<double> observed_;
};

}  // namespace combabc
