#pragma once
// Toy simulators and distances with answers we can compute by hand or by enumeration.
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::testing {

// Output = the bits themselves as doubles; optional busy work to emulate a costly simulator.
class IdentitySimulator : public Simulator {
 public:
  explicit IdentitySimulator(int d, int busy_iterations = 0) : d_(d), busy_(busy_iterations) {}
  int output_size() const override { return d_; }
  void Simulate(const ParameterView& theta,
                RandomStream& /*rng*/,
                std::span<double> out) const override {
    double acc = 0.0;
    for (int i = 0; i < busy_; ++i) acc += std::sqrt(static_cast<double>(i) + acc * 1e-9);
    for (int k = 0; k < d_; ++k) out[k] = theta.bits[k] + acc * 0.0;
  }

 private:
  int d_;
  int busy_;
};

// Output = bits plus Gaussian noise from the candidate's own stream (a stochastic simulator).
class NoisySimulator : public Simulator {
 public:
  NoisySimulator(int d, double sigma) : d_(d), sigma_(sigma) {}
  int output_size() const override { return d_; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    for (int k = 0; k < d_; ++k) out[k] = theta.bits[k] + sigma_ * rng.Normal();
  }

 private:
  int d_;
  double sigma_;
};

// Weighted L1 distance to a target vector: D = sum_k w_k |y_k - target_k| + coupling * y_a * y_b.
class WeightedL1Distance : public Distance {
 public:
  WeightedL1Distance(std::vector<double> target,
                     std::vector<double> weights,
                     int a = 0,
                     int b = 0,
                     double coupling = 0.0)
      : target_(std::move(target)),
        weights_(std::move(weights)),
        a_(a),
        b_(b),
        coupling_(coupling) {}
  std::vector<DistanceComponent> components() const override {
    return {{"l1", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double d = coupling_ * y[a_] * y[b_];
    for (std::size_t k = 0; k < target_.size(); ++k) d += weights_[k] * std::abs(y[k] - target_[k]);
    out[0] = d;
  }

 private:
  std::vector<double> target_, weights_;
  int a_, b_;
  double coupling_;
};

// Vector distance: two L1 halves with their own thresholds, plus an indicator "bit 0 is set".
class SplitDistance : public Distance {
 public:
  explicit SplitDistance(std::vector<double> target) : target_(std::move(target)) {}
  std::vector<DistanceComponent> components() const override {
    return {{"left", ComponentKind::kThreshold, 1.0},
            {"right", ComponentKind::kThreshold, 1.0},
            {"bit0_set", ComponentKind::kIndicator, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    const std::size_t half = target_.size() / 2;
    out[0] = out[1] = 0.0;
    for (std::size_t k = 0; k < target_.size(); ++k) {
      out[k < half ? 0 : 1] += std::abs(y[k] - target_[k]);
    }
    out[2] = y[0] > 0.5 ? 1.0 : 0.0;
  }

 private:
  std::vector<double> target_;
};

// Output = A theta (rows of A as given): a linear model of the bits.
class LinearSimulator : public Simulator {
 public:
  explicit LinearSimulator(std::vector<std::vector<double>> rows) : rows_(std::move(rows)) {}
  int output_size() const override { return static_cast<int>(rows_.size()); }
  void Simulate(const ParameterView& theta,
                RandomStream& /*rng*/,
                std::span<double> out) const override {
    for (std::size_t j = 0; j < rows_.size(); ++j) {
      out[j] = 0.0;
      for (std::size_t k = 0; k < rows_[j].size(); ++k) out[j] += rows_[j][k] * theta.bits[k];
    }
  }

 private:
  std::vector<std::vector<double>> rows_;
};

// Gaussian negative log-likelihood: d = sum_j (y_j - observed_j)^2 / (2 sigma^2).
class GaussianNllDistance : public Distance {
 public:
  GaussianNllDistance(std::vector<double> observed, double sigma)
      : observed_(std::move(observed)), sigma_(sigma) {}
  std::vector<DistanceComponent> components() const override {
    return {{"nll", ComponentKind::kNegLogLikelihood, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double sum = 0.0;
    for (std::size_t j = 0; j < observed_.size(); ++j) {
      sum += (y[j] - observed_[j]) * (y[j] - observed_[j]);
    }
    out[0] = sum / (2.0 * sigma_ * sigma_);
  }

 private:
  std::vector<double> observed_;
  double sigma_;
};

}  // namespace combabc::testing
