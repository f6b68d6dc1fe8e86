#include "combabc/metrics/folded_normal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace combabc {
namespace {

// -log f(y; mu, sigma) without the constant log sigma + log(2 pi) / 2.
double Energy(double y, double mu, double sigma) {
  const double a = std::abs(mu);
  const double z = (y - a) / sigma;
  return 0.5 * z * z - std::log1p(std::exp(-2.0 * y * a / (sigma * sigma)));
}

}  // namespace

double FoldedNormalLogDensity(double y, double mu, double sigma) {
  return -std::log(sigma) - 0.5 * std::log(2.0 * std::numbers::pi) - Energy(y, mu, sigma);
}

double FoldedNormalBestMean(double y, double sigma) {
  if (!(y > sigma)) return 0.0;
  // h(mu) = y tanh(y mu / sigma^2) - mu is concave on mu >= 0 with h(0) = 0, h'(0) = y^2 /
  // sigma^2 - 1 > 0 and h(y) < 0: positive below its root, negative above; bisect to rounding.
  double lo = 0.0;
  double hi = y;
  for (int i = 0; i < 200 && hi - lo > 4.0 * std::numeric_limits<double>::epsilon() * y; ++i) {
    const double mid = 0.5 * (lo + hi);
    (y * std::tanh(y * mid / (sigma * sigma)) - mid > 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double FoldedNormalDeviance(double y, double mu, double sigma) {
  // Energy is flat at its minimum, so the bisection's rounding moves the reference by far less
  // than a unit of it; a candidate at the best mean itself reads 0, never below.
  return std::max(0.0, Energy(y, mu, sigma) - Energy(y, FoldedNormalBestMean(y, sigma), sigma));
}

}  // namespace combabc
