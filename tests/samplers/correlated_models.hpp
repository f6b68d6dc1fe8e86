#pragma once
// Binary problems whose ABC posterior couples bits, with the exact posterior by enumeration
// (pi_eps(theta) ∝ p(theta) 1[D(theta) <= eps] over all 2^d configurations): the truths the
// kernels are checked against (tests/samplers/kernel_exactness_test.cpp,
// bench/bench_engine_correlated.cpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc::testing {

// D = min(Hamming(y, c), Hamming(y, not c)): the posterior sits on c and its complement, so every
// bit's marginal is 1/2 while every pair is perfectly (anti-)correlated: the case where per-bit
// proposals degenerate into rejection sampling.
class ComplementDistance : public Distance {
 public:
  explicit ComplementDistance(std::vector<std::uint8_t> c) : c_(std::move(c)) {}
  std::vector<DistanceComponent> components() const override {
    return {{"hamming", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double to_c = 0.0;
    for (std::size_t k = 0; k < c_.size(); ++k) to_c += (y[k] != 0.0) != (c_[k] != 0);
    out[0] = std::min(to_c, static_cast<double>(c_.size()) - to_c);
  }

 private:
  std::vector<std::uint8_t> c_;
};

// D = (number of neighbours that differ) + 0.5 [y_0 = 0]: chain-coupled bits, each close to its
// neighbour, with a preference for the all-ones end.
class ChainDistance : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"switches", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double d = y[0] == 0.0 ? 0.5 : 0.0;
    for (std::size_t k = 0; k + 1 < y.size(); ++k) d += y[k] != y[k + 1];
    out[0] = d;
  }
};

// D = sum_k w_k |y_k - t_k|: independent bits.
class IndependentDistance : public Distance {
 public:
  IndependentDistance(std::vector<double> target, std::vector<double> weights)
      : target_(std::move(target)), weights_(std::move(weights)) {}
  std::vector<DistanceComponent> components() const override {
    return {{"l1", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double d = 0.0;
    for (std::size_t k = 0; k < target_.size(); ++k) d += weights_[k] * std::abs(y[k] - target_[k]);
    out[0] = d;
  }

 private:
  std::vector<double> target_, weights_;
};

// Marginals and pair correlations of bits under some weighting.
struct BitMoments {
  std::vector<double> mean;               // P(bit k = 1)
  std::vector<std::vector<double>> corr;  // Pearson correlation; 0 where a bit is constant
};

inline BitMoments MomentsFrom(const std::vector<std::vector<double>>& second,
                              std::vector<double> mean) {
  const std::size_t d = mean.size();
  // Filled member by member: the aggregate initialiser trips GCC 12's -Wfree-nonheap-object (a
  // false positive) at -O2 under ThreadSanitizer.
  BitMoments m;
  m.mean = std::move(mean);
  m.corr.resize(d);
  for (auto& row : m.corr) row.assign(d, 0.0);
  for (std::size_t a = 0; a < d; ++a) {
    for (std::size_t b = 0; b < d; ++b) {
      const double va = m.mean[a] * (1 - m.mean[a]), vb = m.mean[b] * (1 - m.mean[b]);
      if (va > 1e-12 && vb > 1e-12) {
        m.corr[a][b] = (second[a][b] - m.mean[a] * m.mean[b]) / std::sqrt(va * vb);
      }
    }
  }
  return m;
}

// The exact ABC posterior's moments, by enumeration (identity simulator: y = bits).
inline BitMoments ExactMoments(const Distance& distance,
                               const std::vector<double>& prior,
                               double eps) {
  const std::size_t d = prior.size();
  std::vector<double> mean(d, 0.0), y(d);
  std::vector<std::vector<double>> second(d, std::vector<double>(d, 0.0));
  double z = 0.0, dist = 0.0;
  for (std::uint64_t c = 0; c < (std::uint64_t{1} << d); ++c) {
    double p = 1.0;
    for (std::size_t k = 0; k < d; ++k) {
      y[k] = static_cast<double>((c >> k) & 1);
      p *= y[k] != 0.0 ? prior[k] : 1.0 - prior[k];
    }
    distance.Evaluate(y, std::span(&dist, 1));
    if (!(dist <= eps)) continue;
    z += p;
    for (std::size_t a = 0; a < d; ++a) {
      if (y[a] == 0.0) continue;
      mean[a] += p;
      for (std::size_t b = 0; b < d; ++b) second[a][b] += y[b] * p;
    }
  }
  for (auto& x : mean) x /= z;
  for (auto& row : second) {
    for (auto& x : row) x /= z;
  }
  return MomentsFrom(second, std::move(mean));
}

// The same moments from a wave's particles under their normalised weights.
inline BitMoments WaveMoments(const WaveRecord& wave) {
  const std::size_t d = wave.particles.at(0).theta.bits.size();
  std::vector<double> mean(d, 0.0);
  std::vector<std::vector<double>> second(d, std::vector<double>(d, 0.0));
  for (const auto& p : wave.particles) {
    for (std::size_t a = 0; a < d; ++a) {
      if (!p.theta.bits[a]) continue;
      mean[a] += p.weight;
      for (std::size_t b = 0; b < d; ++b) second[a][b] += p.theta.bits[b] * p.weight;
    }
  }
  return MomentsFrom(second, std::move(mean));
}

}  // namespace combabc::testing
