// The mode-loss diagnostic as a pure function (FindPatternClasses, ModeLossWarning) on crafted
// populations and proposals.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "combabc/samplers/mode_loss.hpp"

namespace combabc {
namespace {

// A population of `counts[pattern]` equally weighted particles per pattern (2 free bits).
Population Crafted(const std::map<std::vector<std::uint8_t>, int>& counts) {
  Population pop;
  pop.num_free_bits = counts.begin()->first.size();
  for (const auto& [bits, n] : counts) {
    for (int i = 0; i < n; ++i) {
      pop.free_bits.insert(pop.free_bits.end(), bits.begin(), bits.end());
      ++pop.size;
    }
  }
  pop.weights.assign(pop.size, 1.0 / static_cast<double>(pop.size));
  return pop;
}

// log q from a table of probabilities (1e-300 for a pattern not listed).
LogBitsDensity Table(std::map<std::vector<std::uint8_t>, double> q) {
  return [q = std::move(q)](std::span<const std::uint8_t> bits) {
    const auto it = q.find(std::vector<std::uint8_t>(bits.begin(), bits.end()));
    return std::log(it == q.end() ? 1e-300 : it->second);
  };
}

TEST(ModeLoss, FlagsAHeavyPatternProposedWithTinyProbability) {
  // 93 % on 00, 7 % on 11; the proposal gives 11 probability 1e-6.
  const Population pop = Crafted({{{0, 0}, 93}, {{1, 1}, 7}});
  const auto classes = FindPatternClasses(
      pop, Table({{{0, 0}, 0.98}, {{1, 1}, 1e-6}, {{0, 1}, 0.01}, {{1, 0}, 0.01}}), 100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_EQ(classes[0].bits, (std::vector<std::uint8_t>{0, 0}));  // heaviest first
  EXPECT_NEAR(classes[0].mass, 0.93, 1e-12);
  EXPECT_FALSE(classes[0].flagged);
  EXPECT_EQ(classes[1].bits, (std::vector<std::uint8_t>{1, 1}));
  EXPECT_NEAR(classes[1].mass, 0.07, 1e-12);
  EXPECT_NEAR(classes[1].proposal, 1e-6, 1e-18);
  EXPECT_TRUE(classes[1].flagged);

  WaveRecord wave;
  wave.wave = 2;
  wave.pattern_classes = classes;
  EXPECT_EQ(ModeLossWarning(wave),
            "wave 3 proposed pattern 11 (mass 0.07) with probability 1e-06; the posterior may "
            "have lost a mode");
}

TEST(ModeLoss, QuietWhenTheProposalTracksTheMass) {
  const Population pop = Crafted({{{0, 0}, 93}, {{1, 1}, 7}});
  const auto classes =
      FindPatternClasses(pop, Table({{{0, 0}, 0.9}, {{1, 1}, 0.06}, {{0, 1}, 0.02}}), 100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_FALSE(classes[0].flagged);
  EXPECT_FALSE(classes[1].flagged);
  WaveRecord wave;
  wave.pattern_classes = classes;
  EXPECT_EQ(ModeLossWarning(wave), "");
}

TEST(ModeLoss, ManyLightPatternsAreNotChecked) {
  // 1000 particles on 250 patterns of 4 each (mass 0.004 < max(0.01, 5 / 1000)), none of which
  // the proposal proposes: no class is heavy, so nothing is flagged.
  std::map<std::vector<std::uint8_t>, int> counts;
  for (int k = 0; k < 250; ++k) {
    std::vector<std::uint8_t> bits(8);
    for (int j = 0; j < 8; ++j) bits[static_cast<std::size_t>(j)] = (k >> j) & 1;
    counts[bits] = 4;
  }
  const Population pop = Crafted(counts);
  EXPECT_TRUE(FindPatternClasses(pop, Table({}), 1000).empty());
  // The same population checked for a wave of 100 particles: a class needs 0.05.
  EXPECT_TRUE(FindPatternClasses(pop, Table({}), 100).empty());
}

TEST(ModeLoss, HeavyMeansFiveParticlesWorthInSmallWaves) {
  // 4 % of the mass: heavy for waves of 500 particles (5 / 500 = 1 %), not for 100 (5 %).
  const Population pop = Crafted({{{0, 0}, 192}, {{1, 1}, 8}});
  const auto log_q = Table({{{0, 0}, 0.999}, {{1, 1}, 1e-7}});
  const auto big = FindPatternClasses(pop, log_q, 500);
  ASSERT_EQ(big.size(), 2u);
  EXPECT_TRUE(big[1].flagged);
  EXPECT_EQ(FindPatternClasses(pop, log_q, 100).size(), 1u);
  EXPECT_DOUBLE_EQ(ModeLossMinMass(100), 0.05);
  EXPECT_DOUBLE_EQ(ModeLossMinMass(1000), 0.01);
}

TEST(ModeLoss, AFewHeavilyWeightedParticlesAreNoMode) {
  // 11 holds 30 % of the mass in 4 particles (importance weights), never proposed: not checked;
  // with a fifth particle it is a class, and flagged.
  Population pop = Crafted({{{0, 0}, 96}, {{1, 1}, 4}});
  for (std::size_t i = 0; i < pop.size; ++i) pop.weights[i] = i < 96 ? 0.7 / 96 : 0.3 / 4;
  const auto log_q = Table({{{0, 0}, 1.0}});
  EXPECT_EQ(FindPatternClasses(pop, log_q, 100).size(), 1u);
  pop = Crafted({{{0, 0}, 95}, {{1, 1}, 5}});
  for (std::size_t i = 0; i < pop.size; ++i) pop.weights[i] = i < 95 ? 0.7 / 95 : 0.3 / 5;
  const auto classes = FindPatternClasses(pop, log_q, 100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_TRUE(classes[1].flagged);
}

TEST(ModeLoss, FlaggedWhenAWaveExpectsLessThanOneParticle) {
  // q = 0.004 and 0.02 with 100 particles: 0.4 expected (flagged), 2 expected (not).
  const Population pop = Crafted({{{0, 0}, 80}, {{0, 1}, 10}, {{1, 1}, 10}});
  const auto classes =
      FindPatternClasses(pop, Table({{{0, 0}, 0.976}, {{0, 1}, 0.004}, {{1, 1}, 0.02}}), 100);
  ASSERT_EQ(classes.size(), 3u);
  EXPECT_TRUE(classes[1].flagged);   // 01: equal mass, pattern order first
  EXPECT_FALSE(classes[2].flagged);  // 11
}

TEST(ModeLoss, FlaggedWhenProposedTwentyTimesUnderItsMass) {
  // A wave of 10,000 expects 50 particles of 01 (mass 0.2, q = 0.005: 40 times under its mass,
  // flagged) and 200 of 11 (mass 0.2, q = 0.02: 10 times under, kept).
  const Population pop = Crafted({{{0, 0}, 60}, {{0, 1}, 20}, {{1, 1}, 20}});
  const auto classes =
      FindPatternClasses(pop, Table({{{0, 0}, 0.975}, {{0, 1}, 0.005}, {{1, 1}, 0.02}}), 10'000);
  ASSERT_EQ(classes.size(), 3u);
  EXPECT_FALSE(classes[0].flagged);  // 00
  EXPECT_TRUE(classes[1].flagged);   // 01
  EXPECT_FALSE(classes[2].flagged);  // 11
}

TEST(ModeLoss, ABrokenDensityIsRecordedAsAProbability) {
  const Population pop = Crafted({{{0, 0}, 90}, {{1, 1}, 10}});
  const auto classes = FindPatternClasses(
      pop, [](std::span<const std::uint8_t> bits) { return bits[0] ? std::nan("") : 0.5; }, 100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_EQ(classes[0].proposal, 1.0);  // exp(0.5), capped
  EXPECT_FALSE(classes[0].flagged);
  EXPECT_EQ(classes[1].proposal, 0.0);  // NaN
  EXPECT_TRUE(classes[1].flagged);
}

TEST(ModeLoss, LongPatternsAreShortenedInText) {
  std::vector<std::uint8_t> bits(100, 0);
  bits[3] = bits[70] = 1;
  EXPECT_EQ(PatternText(bits),
            std::string(3, '0') + "1" + std::string(60, '0') + "... (2 of 100 bits set)");
}

}  // namespace
}  // namespace combabc
