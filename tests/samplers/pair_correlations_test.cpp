// Pair correlations of a wave (BitMoments, samplers/run_history.hpp): the Pearson correlations of
// its particles' bits under the estimator's weights, against values worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "combabc/samplers/run_history.hpp"

namespace combabc {
namespace {

// Four particles over four bits, prior masses 0.4, 0.1, 0.1, 0.4 (as log importance weights);
// bit 3 is set in every one.
WaveRecord TinyWave() {
  const std::vector<std::vector<std::uint8_t>> bits = {
      {1, 1, 0, 1}, {1, 0, 0, 1}, {0, 1, 1, 1}, {0, 0, 1, 1}};
  const std::vector<double> mass = {0.4, 0.1, 0.1, 0.4};
  WaveRecord wave;
  wave.candidates = 10;
  for (std::size_t i = 0; i < bits.size(); ++i) {
    Particle p;
    p.index = static_cast<std::int64_t>(i);
    p.theta.bits = bits[i];
    p.log_weight = std::log(mass[i]);
    wave.particles.push_back(p);
  }
  return wave;
}

void ExpectMatrix(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_NEAR(got[k], want[k], 1e-12) << "row " << k / 4 << ", column " << k % 4;
  }
}

TEST(PairCorrelations, AreTheWeightedPearsonCorrelationsOfTheParticles) {
  WaveRecord wave = TinyWave();
  ComputeWaveStatistics(wave, Estimator::kImportance);
  // Weights 0.4, 0.1, 0.1, 0.4: bits 0-2 are 1 with probability 1/2 (variance 1/4), and
  // P(b0 b1) = 0.4, P(b0 b2) = 0, P(b1 b2) = 0.1, so r = (P(bi bj) - 1/4) / (1/4) = 0.6, -1, -0.6.
  // Bit 3 is constant: no correlation, reported as 0, also on the diagonal.
  ExpectMatrix(wave.pair_correlations,
               {1, 0.6, -1, 0, 0.6, 1, -0.6, 0, -1, -0.6, 1, 0, 0, 0, 0, 0});
}

TEST(PairCorrelations, ThePaperEstimatorWeighsTheParticlesEqually) {
  WaveRecord wave = TinyWave();
  ComputeWaveStatistics(wave, Estimator::kPaper);
  // P(b0 b1) = P(b1 b2) = 1/4 = 1/2 x 1/2: uncorrelated; bits 0 and 2 still exclude each other.
  ExpectMatrix(wave.pair_correlations, {1, 0, -1, 0, 0, 1, 0, 0, -1, 0, 1, 0, 0, 0, 0, 0});
}

TEST(PairCorrelations, AWaveWithoutParticlesHasNone) {
  WaveRecord wave = TinyWave();
  ComputeWaveStatistics(wave, Estimator::kImportance);
  wave.particles.clear();
  ComputeWaveStatistics(wave, Estimator::kImportance);
  EXPECT_TRUE(wave.pair_correlations.empty());
}

// The matrix is kept up to kMaxPairCorrelationBits bits and not beyond (its cost grows as d^2).
TEST(PairCorrelations, AreKeptUpToTheirBitLimit) {
  for (const std::size_t d : {kMaxPairCorrelationBits, kMaxPairCorrelationBits + 1}) {
    WaveRecord wave;
    wave.candidates = 4;
    for (int i = 0; i < 4; ++i) {
      Particle p;
      p.index = i;
      p.theta.bits.assign(d, static_cast<std::uint8_t>(i & 1));
      p.theta.bits[0] = static_cast<std::uint8_t>(i >> 1);
      wave.particles.push_back(p);
    }
    ComputeWaveStatistics(wave, Estimator::kPaper);
    if (d <= kMaxPairCorrelationBits) {
      ASSERT_EQ(wave.pair_correlations.size(), d * d);
      EXPECT_DOUBLE_EQ(wave.pair_correlations[1 * d + 2], 1.0);  // bits 1 and 2 move together
      EXPECT_DOUBLE_EQ(wave.pair_correlations[0 * d + 1], 0.0);  // bit 0 is independent of them
    } else {
      EXPECT_TRUE(wave.pair_correlations.empty());
    }
  }
}

}  // namespace
}  // namespace combabc
