#pragma once
// Mixed problems built to have minor modes that need a different value of the real (issue 23):
// 8 bits and one real theta ~ U(-2, 2), two outputs with Gaussian noise, observed (0, 0), each
// with its own threshold:
//   y1 = cost(b) + 0.3 e1,   y2 = theta - m(b) + 0.1 e2.
// The main pattern B = (1,1,1,1,0,0,0,0) costs 0 and needs theta near 0; two minor patterns cost
// 0.85 and need theta near +1 (m = 1) and -1 (m = -1); they carry 0.070 of the posterior each,
// every other pattern almost nothing (a cost of 1.5 per bit away from B). Two variants:
//  - kSingleFlips: the minor patterns are B with b0 = 0 and B with b7 = 1 (each one bit away;
//    cost(b) = 0.85 (1 - b0) + 0.85 b7 + 1.5 per other bit away from B, m(b) = (1 - b0) - b7);
//  - kJointFlips: the minor patterns are B with bits 0-2 flipped and B with bits 5-7 flipped
//    (three bits away, flipped together: the population's bits are strongly correlated).
// The exact ABC posterior is a sum over the 256 patterns of a quadrature over theta:
// P(|y_k| <= eps_k | b, theta) = Phi((eps_k - mu_k) / s_k) - Phi((-eps_k - mu_k) / s_k).
//
// What the kernels do (tests/samplers/minor_modes_test.cpp, docs/benchmarks.md): on kSingleFlips
// every pair keeps both modes; on kJointFlips the `independent` kernel proposes a minor pattern
// with the product of its three bits' marginals (about 0.07^3), and with either continuous
// kernel both modes are lost (masses 0, theta's sd 0.12 against 0.39): the failure the mode-loss
// diagnostic must warn about. The `logistic` and `ancestor` kernels keep them.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::testing::minor_modes {

constexpr int kBits = 8;
constexpr double kMinorCost = 0.85, kCost = 1.5, kNoise1 = 0.3, kNoise2 = 0.1;
// The threshold lists of the two outputs, wave by wave.
inline const std::vector<double> kEps1 = {3.0, 1.0, 0.6, 0.4};
inline const std::vector<double> kEps2 = {2.0, 0.8, 0.3, 0.1};

enum class Variant { kSingleFlips, kJointFlips };

inline const char* Name(Variant v) {
  return v == Variant::kSingleFlips ? "single_flips" : "joint_flips";
}

// +1 for the minor pattern that needs theta near +1, -1 for the one that needs it near -1, else 0.
inline int MinorMode(Variant v, std::span<const std::uint8_t> b) {
  static constexpr std::array<std::uint8_t, kBits> kMain = {1, 1, 1, 1, 0, 0, 0, 0};
  int away = 0, low = 0, high = 0;  // bits away from B: all, among bits 0-2, among bits 5-7
  for (int k = 0; k < kBits; ++k) {
    const bool off = b[k] != kMain[k];
    away += off ? 1 : 0;
    low += off && k < 3 ? 1 : 0;
    high += off && k >= 5 ? 1 : 0;
  }
  if (v == Variant::kSingleFlips) {
    if (away == 1 && !b[0]) return 1;
    if (away == 1 && b[7]) return -1;
    return 0;
  }
  if (away == 3 && low == 3) return 1;
  if (away == 3 && high == 3) return -1;
  return 0;
}

// The outputs' means given the bits and theta.
inline std::array<double, 2> Means(Variant v, std::span<const std::uint8_t> b, double theta) {
  static constexpr std::array<std::uint8_t, kBits> kMain = {1, 1, 1, 1, 0, 0, 0, 0};
  if (v == Variant::kSingleFlips) {
    double y1 = kMinorCost * (1 - b[0]) + kMinorCost * b[7];
    for (int k = 1; k <= 3; ++k) y1 += kCost * (1 - b[k]);
    for (int k = 4; k <= 6; ++k) y1 += kCost * b[k];
    return {y1, theta - ((1 - b[0]) - b[7])};
  }
  const int mode = MinorMode(v, b);
  double away = 0.0;
  for (int k = 0; k < kBits; ++k) away += b[k] != kMain[k] ? 1.0 : 0.0;
  return {mode != 0 ? kMinorCost : kCost * away, theta - mode};
}

class Simulator final : public combabc::Simulator {
 public:
  explicit Simulator(Variant v) : v_(v) {}
  int output_size() const override { return 2; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    const auto m = Means(v_, theta.bits, theta.reals[0]);
    out[0] = m[0] + kNoise1 * rng.Normal();
    out[1] = m[1] + kNoise2 * rng.Normal();
  }

 private:
  Variant v_;
};

// |y1| and |y2|, one threshold each.
class Distance final : public combabc::Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"y1", ComponentKind::kThreshold, 1.0}, {"y2", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0]);
    out[1] = std::abs(y[1]);
  }
};

inline ParameterSpace Space() {
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -2.0;
  prior.high = 2.0;
  return ParameterSpace(BinarySpace::Independent(kBits), {{"theta", prior}});
}

inline SmcOptions Options(BinaryKernelKind binary,
                          ContinuousKernelKind continuous,
                          int n,
                          std::uint64_t seed) {
  SmcOptions o;
  o.num_waves = static_cast<int>(kEps1.size());
  o.accepted_per_wave = n;
  o.seed = seed;
  o.threads = 2;
  o.proposal.binary = binary;
  o.proposal.continuous = continuous;
  for (const auto* eps : {&kEps1, &kEps2}) {
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = *eps;
    o.thresholds.push_back(s);
  }
  return o;
}

// The exact ABC posterior at the last wave's thresholds.
struct Exact {
  std::vector<double> bit_mean;  // P(b_k = 1)
  double mean = 0.0, sd = 0.0;   // of theta
  double minor_plus = 0.0;       // P(the minor pattern that needs theta near +1)
  double minor_minus = 0.0;      // P(the minor pattern that needs theta near -1)
};

inline double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

inline Exact ExactPosterior(Variant v) {
  const double eps1 = kEps1.back(), eps2 = kEps2.back();
  constexpr int kSteps = 4000;
  constexpr double kLow = -2.0, kHigh = 2.0, kH = (kHigh - kLow) / kSteps;
  Exact e;
  e.bit_mean.assign(kBits, 0.0);
  double z = 0.0, m1 = 0.0, m2 = 0.0;
  std::array<std::uint8_t, kBits> b{};
  for (unsigned c = 0; c < (1U << kBits); ++c) {
    for (int k = 0; k < kBits; ++k) b[k] = static_cast<std::uint8_t>((c >> k) & 1U);
    const double mu1 = Means(v, b, 0.0)[0];
    const double p1 = Phi((eps1 - mu1) / kNoise1) - Phi((-eps1 - mu1) / kNoise1);
    double mass = 0.0, t1 = 0.0, t2 = 0.0;
    for (int i = 0; i < kSteps; ++i) {
      const double t = kLow + (i + 0.5) * kH;
      const double mu2 = Means(v, b, t)[1];
      const double f = p1 * (Phi((eps2 - mu2) / kNoise2) - Phi((-eps2 - mu2) / kNoise2));
      mass += f;
      t1 += f * t;
      t2 += f * t * t;
    }
    z += mass;
    m1 += t1;
    m2 += t2;
    for (int k = 0; k < kBits; ++k) e.bit_mean[k] += b[k] ? mass : 0.0;
    const int mode = MinorMode(v, b);
    if (mode == 1) e.minor_plus = mass;
    if (mode == -1) e.minor_minus = mass;
  }
  for (double& x : e.bit_mean) x /= z;
  e.minor_plus /= z;
  e.minor_minus /= z;
  e.mean = m1 / z;
  e.sd = std::sqrt(m2 / z - e.mean * e.mean);
  return e;
}

}  // namespace combabc::testing::minor_modes
