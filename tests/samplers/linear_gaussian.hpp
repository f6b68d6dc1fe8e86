#pragma once
// The linear Gaussian model y = sum_k w_k b_k + theta + sigma e with |y - y*| as the distance, and
// its exact ABC posterior by enumeration over the bits x quadrature over theta: the mixed toy of
// continuous_test.cpp, the Monte-Carlo error coverage test and bench_engine_coverage.
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::testing {

inline double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// y = sum_k w_k b_k + theta + sigma e, e ~ N(0, 1) from the candidate's stream.
class LinearGaussianSimulator : public Simulator {
 public:
  LinearGaussianSimulator(std::vector<double> w, double sigma) : w_(std::move(w)), sigma_(sigma) {}
  int output_size() const override { return 1; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    double y = theta.reals[0] + sigma_ * rng.Normal();
    for (std::size_t k = 0; k < w_.size(); ++k) y += w_[k] * theta.bits[k];
    out[0] = y;
  }

 private:
  std::vector<double> w_;
  double sigma_;
};

class AbsoluteDistance : public Distance {
 public:
  explicit AbsoluteDistance(double observed) : observed_(observed) {}
  std::vector<DistanceComponent> components() const override {
    return {{"abs", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0] - observed_);
  }

 private:
  double observed_;
};

// Exact ABC posterior of the mixed toy: p(b) p(theta) P(|y* - y| <= eps | b, theta), with
// P = Phi((y + eps - m)/sigma) - Phi((y - eps - m)/sigma), m = w.b + theta; the integral over
// theta by the midpoint rule on the prior's support.
struct Exact {
  std::vector<double> bit_mean;
  std::vector<double> configuration_mass;  // index c: bit k is bit k of c
  double mean = 0, var = 0;
};
inline Exact ExactPosterior(const std::vector<double>& w,
                            const std::vector<double>& bit_prior,
                            const ContinuousPrior& prior,
                            double sigma,
                            double y,
                            double eps,
                            double lo,
                            double hi) {
  const std::size_t d = w.size();
  Exact e;
  e.bit_mean.assign(d, 0.0);
  double z = 0, m1 = 0, m2 = 0;
  const int steps = 20000;
  const double h = (hi - lo) / steps;
  for (std::uint32_t c = 0; c < (1u << d); ++c) {
    double pb = 1.0, shift = 0.0;
    for (std::size_t k = 0; k < d; ++k) {
      const bool one = (c >> k) & 1;
      pb *= one ? bit_prior[k] : 1.0 - bit_prior[k];
      shift += one ? w[k] : 0.0;
    }
    double mass = 0, t1 = 0, t2 = 0;
    for (int i = 0; i < steps; ++i) {
      const double t = lo + (i + 0.5) * h;
      const double m = shift + t;
      const double f = std::exp(prior.LogDensity(t)) *
                       (sigma > 0 ? Phi((y + eps - m) / sigma) - Phi((y - eps - m) / sigma)
                                  : (std::abs(m - y) <= eps ? 1.0 : 0.0)) *
                       h;
      mass += f;
      t1 += f * t;
      t2 += f * t * t;
    }
    e.configuration_mass.push_back(pb * mass);
    z += pb * mass;
    m1 += pb * t1;
    m2 += pb * t2;
    for (std::size_t k = 0; k < d; ++k) {
      if ((c >> k) & 1) e.bit_mean[k] += pb * mass;
    }
  }
  for (auto& x : e.bit_mean) x /= z;
  for (auto& x : e.configuration_mass) x /= z;
  e.mean = m1 / z;
  e.var = m2 / z - e.mean * e.mean;
  return e;
}

}  // namespace combabc::testing
