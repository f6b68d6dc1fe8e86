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

// log(q / p) from a table of ratios, the same for every particle of a pattern (1e-300 for a
// pattern not listed). A pattern's share of the new wave is then its mass times its ratio,
// normalised: the tables below give ratio = share / mass.
LogProposalRatio Table(std::map<std::vector<std::uint8_t>, double> ratio) {
  return [ratio = std::move(ratio)](std::span<const std::uint8_t> bits, std::span<const double>) {
    const auto it = ratio.find(std::vector<std::uint8_t>(bits.begin(), bits.end()));
    return std::log(it == ratio.end() ? 1e-300 : it->second);
  };
}

// The classes with the same ratio for the bits alone as for bits and reals.
std::vector<PatternClass> Find(const Population& pop, const LogProposalRatio& ratio, int n) {
  return FindPatternClasses(
      pop, ratio, [&](std::span<const std::uint8_t> bits) { return ratio(bits, {}); }, n);
}

TEST(ModeLoss, FlagsAHeavyPatternGivenATinyShare) {
  // 93 % on 00, 7 % on 11; the proposal gives 11 a millionth of its mass's ratio.
  const Population pop = Crafted({{{0, 0}, 93}, {{1, 1}, 7}});
  const auto classes = Find(pop, Table({{{0, 0}, 1.0}, {{1, 1}, 1e-6}}), 100);
  // The classes of bit 1 = 1 and of bit 2 = 1 are flagged too, but they are 11: not recorded.
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_EQ(classes[0].bits, (std::vector<std::uint8_t>{0, 0}));  // heaviest first
  EXPECT_NEAR(classes[0].mass, 0.93, 1e-12);
  EXPECT_FALSE(classes[0].flagged);
  EXPECT_EQ(classes[1].bits, (std::vector<std::uint8_t>{1, 1}));
  EXPECT_NEAR(classes[1].mass, 0.07, 1e-12);
  EXPECT_NEAR(classes[1].proposal, 0.07e-6 / (0.93 + 0.07e-6), 1e-18);
  EXPECT_TRUE(classes[1].flagged);

  WaveRecord wave;
  wave.wave = 2;
  wave.pattern_classes = classes;
  EXPECT_EQ(ModeLossWarning(wave),
            "wave 3 proposed pattern 11 (mass 0.07) with probability 7.5e-08; the posterior may "
            "have lost a mode");
}

TEST(ModeLoss, QuietWhenTheProposalTracksTheMass) {
  const Population pop = Crafted({{{0, 0}, 93}, {{1, 1}, 7}});
  const auto classes = Find(pop, Table({{{0, 0}, 0.9}, {{1, 1}, 1.2}}), 100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_FALSE(classes[0].flagged);
  EXPECT_FALSE(classes[1].flagged);
  WaveRecord wave;
  wave.pattern_classes = classes;
  EXPECT_EQ(ModeLossWarning(wave), "");
}

TEST(ModeLoss, ManyLightPatternsAreNotChecked) {
  // 1000 particles on 250 patterns of 4 each (mass 0.004 < max(0.01, 5 / 1000)), all proposed
  // alike: no whole pattern is heavy, and no bit's value is under-proposed.
  std::map<std::vector<std::uint8_t>, int> counts;
  for (int k = 0; k < 250; ++k) {
    std::vector<std::uint8_t> bits(8);
    for (int j = 0; j < 8; ++j) bits[static_cast<std::size_t>(j)] = (k >> j) & 1;
    counts[bits] = 4;
  }
  const Population pop = Crafted(counts);
  EXPECT_TRUE(Find(pop, Table({}), 1000).empty());
  // The same population checked for a wave of 100 particles: a class needs 0.05.
  EXPECT_TRUE(Find(pop, Table({}), 100).empty());
}

TEST(ModeLoss, HeavyMeansFiveParticlesWorthInSmallWaves) {
  // 4 % of the mass: heavy for waves of 500 particles (5 / 500 = 1 %), not for 100 (5 %).
  const Population pop = Crafted({{{0, 0}, 192}, {{1, 1}, 8}});
  const auto ratio = Table({{{0, 0}, 1.0}, {{1, 1}, 1e-7}});
  const auto big = Find(pop, ratio, 500);
  ASSERT_EQ(big.size(), 2u);
  EXPECT_TRUE(big[1].flagged);
  EXPECT_EQ(Find(pop, ratio, 100).size(), 1u);
  EXPECT_DOUBLE_EQ(ModeLossMinMass(100), 0.05);
  EXPECT_DOUBLE_EQ(ModeLossMinMass(1000), 0.01);
}

TEST(ModeLoss, AFewHeavilyWeightedParticlesAreNoMode) {
  // 11 holds 30 % of the mass in 4 particles (importance weights), never proposed: not checked;
  // with a fifth particle it is a class, and flagged.
  Population pop = Crafted({{{0, 0}, 96}, {{1, 1}, 4}});
  for (std::size_t i = 0; i < pop.size; ++i) pop.weights[i] = i < 96 ? 0.7 / 96 : 0.3 / 4;
  const auto ratio = Table({{{0, 0}, 1.0}});
  EXPECT_EQ(Find(pop, ratio, 100).size(), 1u);
  pop = Crafted({{{0, 0}, 95}, {{1, 1}, 5}});
  for (std::size_t i = 0; i < pop.size; ++i) pop.weights[i] = i < 95 ? 0.7 / 95 : 0.3 / 5;
  const auto classes = Find(pop, ratio, 100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_TRUE(classes[1].flagged);
  // Issue 35: eight particles, one of which carries nearly all of the class's 12 %: an effective
  // sample size of 1.3, however many particles hold the pattern.
  pop = Crafted({{{0, 0}, 92}, {{1, 1}, 8}});
  for (std::size_t i = 0; i < pop.size; ++i) {
    pop.weights[i] = i < 92 ? 0.88 / 92 : i == 92 ? 0.113 : 0.001;
  }
  EXPECT_EQ(Find(pop, ratio, 100).size(), 1u);
}

TEST(ModeLoss, FlaggedWhenAWaveExpectsLessThanOneParticle) {
  // Shares 0.004 and 0.02 with 100 particles: 0.4 expected (flagged), 2 expected (not).
  const Population pop = Crafted({{{0, 0}, 80}, {{0, 1}, 10}, {{1, 1}, 10}});
  const auto classes =
      Find(pop, Table({{{0, 0}, 0.976 / 0.8}, {{0, 1}, 0.004 / 0.1}, {{1, 1}, 0.02 / 0.1}}), 100);
  ASSERT_EQ(classes.size(), 3u);
  EXPECT_TRUE(classes[1].flagged);  // 01: equal mass, pattern order first
  EXPECT_NEAR(classes[1].proposal, 0.004, 1e-15);
  EXPECT_FALSE(classes[2].flagged);  // 11
}

TEST(ModeLoss, FlaggedWhenProposedTwentyTimesUnderItsMass) {
  // A wave of 10,000 expects 50 particles of 01 (mass 0.2, share 0.005: 40 times under its mass,
  // flagged) and 200 of 11 (mass 0.2, share 0.02: 10 times under, kept).
  const Population pop = Crafted({{{0, 0}, 60}, {{0, 1}, 20}, {{1, 1}, 20}});
  const auto classes = Find(
      pop, Table({{{0, 0}, 0.975 / 0.6}, {{0, 1}, 0.005 / 0.2}, {{1, 1}, 0.02 / 0.2}}), 10'000);
  ASSERT_EQ(classes.size(), 3u);
  EXPECT_FALSE(classes[0].flagged);  // 00
  EXPECT_TRUE(classes[1].flagged);   // 01
  EXPECT_FALSE(classes[2].flagged);  // 11
}

TEST(ModeLoss, ABrokenDensityIsRecordedAsAProbability) {
  const Population pop = Crafted({{{0, 0}, 90}, {{1, 1}, 10}});
  const auto classes = Find(
      pop,
      [](std::span<const std::uint8_t> bits, std::span<const double>) {
        return bits[0] ? std::nan("") : 0.5;
      },
      100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_NEAR(classes[0].proposal, 1.0, 1e-12);  // all of the share
  EXPECT_FALSE(classes[0].flagged);
  EXPECT_EQ(classes[1].proposal, 0.0);  // NaN
  EXPECT_TRUE(classes[1].flagged);
}

// Issue 35, "a lost mode through its reals": the bits of 11 are proposed as often as their mass,
// but with reals far from its particles' (the product kernels draw the reals without regard to
// the bits), so that the proposal's density at 11's particles is a thousandth of the rest's.
TEST(ModeLoss, SeesAPatternLostThroughItsReals) {
  Population pop = Crafted({{{0, 0}, 90}, {{1, 1}, 10}});
  pop.num_reals = 1;
  for (std::size_t i = 0; i < pop.size; ++i) pop.reals.push_back(i < 90 ? 0.0 : 1.0);
  const auto classes = FindPatternClasses(
      pop,
      [](std::span<const std::uint8_t>, std::span<const double> reals) {
        return reals[0] > 0.5 ? std::log(1e-3) : 0.0;
      },
      [](std::span<const std::uint8_t>) { return 0.0; },
      100);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_EQ(classes[1].bits, (std::vector<std::uint8_t>{1, 1}));
  EXPECT_TRUE(classes[1].flagged);
  EXPECT_NEAR(classes[1].proposal, 1e-4 / (0.9 + 1e-4), 1e-15);
}

// The particles the new wave's thresholds still accept stand for its target: 11, heavy at the
// old thresholds, has none of them, so that its loss is the schedule's, not the proposal's.
TEST(ModeLoss, AClassTheNewThresholdsDropIsNotHeavy) {
  Population pop = Crafted({{{0, 0}, 90}, {{1, 1}, 10}});
  const auto ratio = Table({{{0, 0}, 1.0}, {{1, 1}, 1e-6}});
  EXPECT_EQ(Find(pop, ratio, 100).size(), 2u);
  for (std::size_t i = 0; i < pop.size; ++i) pop.within_next.push_back(i < 90 ? 1 : 0);
  const auto classes = Find(pop, ratio, 100);
  ASSERT_EQ(classes.size(), 1u);
  EXPECT_NEAR(classes[0].mass, 1.0, 1e-12);
}

// The paper estimator's equal weights stand for the previous proposal times the acceptance: a
// share then takes each particle's log p/q_t too. 11 has q/p = 1e-3 under the new proposal, as
// under the previous one (p/q_t = 1e3): the new proposal gives it what the old one did, no loss.
TEST(ModeLoss, ThePaperEstimatorsSharesAreRelativeToThePreviousProposal) {
  const Population pop = Crafted({{{0, 0}, 90}, {{1, 1}, 10}});
  const auto ratio = Table({{{0, 0}, 1.0}, {{1, 1}, 1e-3}});
  const auto bits_ratio = [&](std::span<const std::uint8_t> bits) { return ratio(bits, {}); };
  EXPECT_TRUE(FindPatternClasses(pop, ratio, bits_ratio, 100)[1].flagged);
  std::vector<double> log_p_over_q(pop.size, 0.0);
  for (std::size_t i = 90; i < 100; ++i) log_p_over_q[i] = std::log(1e3);
  const auto classes = FindPatternClasses(pop, ratio, bits_ratio, 100, log_p_over_q);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_FALSE(classes[1].flagged);
  EXPECT_NEAR(classes[1].proposal, 0.1, 1e-12);
}

// Issue 35: where no two particles share a pattern (36 clamps, 500 distinct particles) no whole
// pattern is heavy, but a bit's value or a pair's can be, and is flagged when the proposal stops
// giving it particles. 200 distinct patterns of 12 bits: bit 1 = 0 in 20 of them (10 %), which the
// proposal gives 1e-4 of the ratio of the rest; bits 2 and 3 both 1 in 25 others (12.5 %, each
// bit 1 alone in 50 %), which it gives 1e-3.
TEST(ModeLoss, FlagsABitsValueOrAPairsWhereNoPatternRepeats) {
  std::map<std::vector<std::uint8_t>, int> counts;
  for (int k = 0; k < 200; ++k) {
    std::vector<std::uint8_t> bits(12);
    // k's parity in bit 2, the rest of it in bits 4-11: 200 distinct patterns.
    for (int j = 3; j < 11; ++j) bits[static_cast<std::size_t>(j)] = (k >> (j - 2)) & 1;
    bits[0] = k % 10 == 0 ? 0 : 1;
    bits[1] = k % 2 == 1 ? 1 : 0;
    bits[2] = k % 2 == 1 ? (k % 8 == 1 ? 1 : 0) : (k % 8 < 6 ? 1 : 0);
    counts[bits] = 1;
  }
  ASSERT_EQ(counts.size(), 200u);
  const Population pop = Crafted(counts);
  const auto classes = Find(
      pop,
      [](std::span<const std::uint8_t> bits, std::span<const double>) {
        if (bits[0] == 0) return std::log(1e-4);
        return bits[1] && bits[2] ? std::log(1e-3) : 0.0;
      },
      500);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_EQ(PatternText(classes[0].bits), "-11---------");
  EXPECT_NEAR(classes[0].mass, 0.125, 1e-12);
  EXPECT_TRUE(classes[0].flagged);
  EXPECT_EQ(PatternText(classes[1].bits), "0-----------");
  EXPECT_NEAR(classes[1].mass, 0.1, 1e-12);
  EXPECT_TRUE(classes[1].flagged);
  WaveRecord wave;
  wave.wave = 1;
  wave.pattern_classes = classes;
  EXPECT_EQ(ModeLossWarning(wave).substr(0, 48),
            "wave 2 proposed pattern -11--------- (mass 0.125");
}

TEST(ModeLoss, LongPatternsAreShortenedInText) {
  std::vector<std::uint8_t> bits(100, 0);
  bits[3] = bits[70] = 1;
  EXPECT_EQ(PatternText(bits),
            std::string(3, '0') + "1" + std::string(60, '0') + "... (2 of 100 bits set)");
  std::vector<std::uint8_t> some(100, kAnyBit);
  some[3] = 1;
  some[70] = 0;
  EXPECT_EQ(PatternText(some), "bit 4 = 1, bit 71 = 0");
  EXPECT_EQ(PatternText({kAnyBit, 1, 0}), "-10");
}

}  // namespace
}  // namespace combabc
