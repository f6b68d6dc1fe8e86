#pragma once
// log(e^a + e^b) without overflow, either of which may be -inf: the logistic kernel's mixture
// density and the multi-fidelity sampler's running log sum of squared weights.
#include <algorithm>
#include <cmath>
#include <limits>

namespace combabc {

inline double LogSumExp(double a, double b) {
  const double high = std::max(a, b);
  if (high == -std::numeric_limits<double>::infinity()) return high;
  return high + std::log1p(std::exp(std::min(a, b) - high));
}

}  // namespace combabc
