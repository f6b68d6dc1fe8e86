#include "combabc/distances/euclidean_distance.hpp"

#include <cmath>
#include <utility>

#include "combabc/core/check.hpp"

namespace combabc {

EuclideanDistance::EuclideanDistance(std::vector<double> observed)
    : observed_(std::move(observed)) {}

std::vector<DistanceComponent> EuclideanDistance::components() const {
  return {{"euclidean", ComponentKind::kThreshold, 1.0}};
}

void EuclideanDistance::Evaluate(std::span<const double> simulated, std::span<double> out) const {
  COMBABC_CHECK(simulated.size() == observed_.size() && out.size() == 1);
  double sum = 0.0;
  for (std::size_t i = 0; i < observed_.size(); ++i) {
    const double diff = simulated[i] - observed_[i];
    sum += diff * diff;
  }
  out[0] = std::sqrt(sum);
}

}  // namespace combabc
