// Stopping rules, vector distances, and the tempering of stuck bits (Eq. 3).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

using testing::IdentitySimulator;
using testing::NoisySimulator;
using testing::SplitDistance;
using testing::WeightedL1Distance;

ThresholdSchedule List(std::vector<double> values) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = std::move(values);
  return s;
}

// Outputs 5 everywhere: never within threshold 0 of any 0/1 target.
class FarSimulator : public Simulator {
 public:
  int output_size() const override { return 8; }
  void Simulate(const ParameterView&, RandomStream&, std::span<double> out) const override {
    for (double& v : out) v = 5.0;
  }
};

struct Toy {
  ParameterSpace space{BinarySpace::Independent(8)};
  IdentitySimulator sim{8};
  WeightedL1Distance dist{{1, 0, 1, 0, 1, 0, 1, 0}, {1, 1, 1, 1, 1, 1, 1, 1}};
  SmcProblem problem() const { return {&space, &sim, &dist}; }
};

TEST(Stopping, BudgetStopsAtExactlyMaxSimulations) {
  Toy toy;
  SmcOptions o;
  o.accepted_per_wave = 100;
  o.thresholds = {List({8, 4, 2, 1, 0})};
  o.max_simulations = 700;
  const auto h = RunCombinatorialSmc(toy.problem(), o);
  EXPECT_EQ(h.summary.termination, Termination::kBudgetExhausted);
  EXPECT_EQ(h.summary.simulations, 700);
  EXPECT_FALSE(h.waves.back().complete);
  for (std::size_t t = 0; t + 1 < h.waves.size(); ++t) EXPECT_TRUE(h.waves[t].complete);
}

TEST(Stopping, MinAcceptanceRateGivesUpOnceTheFloorApplies) {
  Toy toy;
  SmcOptions o;
  o.num_waves = 1;
  o.accepted_per_wave = 50;
  o.thresholds = {List({0})};  // exact match: rate 1/256
  o.min_acceptance_rate = 0.1;
  o.acceptance_floor_after = 200;
  const auto h = RunCombinatorialSmc(toy.problem(), o);
  EXPECT_EQ(h.summary.termination, Termination::kAcceptanceRateTooLow);
  // Judged at candidate 200 exactly: ~0.8 accepted there, far below 0.1 x 200.
  EXPECT_EQ(h.waves[0].candidates, 200);
  EXPECT_LT(h.waves[0].accepted, 20);
  EXPECT_NE(h.summary.message.find("below min_acceptance_rate"), std::string::npos)
      << h.summary.message;
}

TEST(Stopping, DefaultsEndAHopelessRun) {
  // A simulator whose distance is never within the threshold: with the default floor the run
  // ends after acceptance_floor_after candidates, not never.
  Toy toy;
  FarSimulator far;
  SmcOptions o;
  o.num_waves = 1;
  o.accepted_per_wave = 10;
  o.thresholds = {List({0})};
  const SmcOptions defaults;
  EXPECT_GT(defaults.min_acceptance_rate, 0.0);
  EXPECT_GT(defaults.max_simulations, 0);
  const auto h = RunCombinatorialSmc({&toy.space, &far, &toy.dist}, o);
  EXPECT_EQ(h.summary.termination, Termination::kAcceptanceRateTooLow);
  EXPECT_EQ(h.waves[0].candidates, defaults.acceptance_floor_after);
  EXPECT_EQ(h.waves[0].accepted, 0);
}

TEST(Stopping, ZeroMeansNoFloor) {
  // Without the floor or a budget this run would never end; a budget shows the floor is off.
  Toy toy;
  FarSimulator far;
  SmcOptions o;
  o.num_waves = 1;
  o.accepted_per_wave = 10;
  o.thresholds = {List({0})};
  o.min_acceptance_rate = 0;
  o.acceptance_floor_after = 10;
  o.max_simulations = 3000;
  const auto h = RunCombinatorialSmc({&toy.space, &far, &toy.dist}, o);
  EXPECT_EQ(h.summary.termination, Termination::kBudgetExhausted);
  EXPECT_EQ(h.summary.simulations, 3000);
}

TEST(Stopping, WallTimeLimitStopsAtABatchBoundary) {
  const ParameterSpace space(BinarySpace::Independent(8));
  IdentitySimulator slow(8, 20000);
  WeightedL1Distance dist({1, 0, 1, 0, 1, 0, 1, 0}, {1, 1, 1, 1, 1, 1, 1, 1});
  SmcOptions o;
  o.accepted_per_wave = 1000000;
  o.batch_size = 64;
  o.max_wall_time_s = 0.05;
  const auto h = RunCombinatorialSmc({&space, &slow, &dist}, o);
  EXPECT_EQ(h.summary.termination, Termination::kWallTimeExceeded);
  EXPECT_FALSE(h.waves.back().complete);
}

class StopAfter : public SmcObserver {
 public:
  explicit StopAfter(int batches) : left_(batches) {}
  void OnBatch(const BatchProgress&, std::span<const Particle>) override { --left_; }
  bool ShouldStop() override { return left_ <= 0; }

 private:
  int left_;
};

TEST(Stopping, ObserverCanInterrupt) {
  Toy toy;
  SmcOptions o;
  o.accepted_per_wave = 200;
  o.batch_size = 10;
  StopAfter stop(3);
  const auto h = RunCombinatorialSmc(toy.problem(), o, &stop);
  EXPECT_EQ(h.summary.termination, Termination::kInterrupted);
  EXPECT_EQ(h.waves[0].candidates, 30);
}

TEST(Stopping, AdaptiveQuantileStopsWhenTheTargetIsReached) {
  Toy toy;
  SmcOptions o;
  o.num_waves = 20;
  o.accepted_per_wave = 200;
  o.thresholds.resize(1);
  o.thresholds[0].target = 1.0;
  const auto h = RunCombinatorialSmc(toy.problem(), o);
  EXPECT_EQ(h.summary.termination, Termination::kTargetReached);
  EXPECT_EQ(h.waves.back().thresholds[0], 1.0);
  EXPECT_LT(h.waves.size(), 20u);
  for (std::size_t t = 1; t < h.waves.size(); ++t) {
    EXPECT_LE(h.waves[t].thresholds[0], h.waves[t - 1].thresholds[0]);
  }
  for (const auto& p : h.waves.back().particles) EXPECT_LE(p.distance[0], 1.0);
}

TEST(Stopping, MaxWavesWhenTheTargetIsOutOfReach) {
  const ParameterSpace space(BinarySpace::Independent(4));
  NoisySimulator sim(4, 0.3);
  WeightedL1Distance dist({1, 0, 1, 0}, {1, 1, 1, 1});
  SmcOptions o;
  o.num_waves = 3;
  o.accepted_per_wave = 50;
  o.thresholds.resize(1);
  o.thresholds[0].target = 1e-9;
  const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
  EXPECT_EQ(h.summary.termination, Termination::kMaxWaves);
  EXPECT_EQ(h.waves.size(), 3u);
  EXPECT_EQ(h.summary.waves_completed, 3);
}

TEST(VectorDistance, EveryComponentMeetsItsThresholdAndIndicatorsTheirValue) {
  const ParameterSpace space(BinarySpace::Independent(8));
  IdentitySimulator sim(8);
  SplitDistance dist({1, 0, 1, 0, 1, 1, 0, 0});
  SmcOptions o;
  o.num_waves = 3;
  o.accepted_per_wave = 100;
  o.thresholds = {List({4, 2, 1}), List({3, 1, 0})};
  const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  for (const auto& w : h.waves) {
    ASSERT_EQ(w.thresholds.size(), 2u);
    for (const auto& p : w.particles) {
      EXPECT_LE(p.distance[0], w.thresholds[0]);
      EXPECT_LE(p.distance[1], w.thresholds[1]);
      EXPECT_EQ(p.distance[2], 1.0);
      EXPECT_EQ(p.theta.bits[0], 1);
    }
  }
}

// Counts how often bit 0 is proposed as 1, per wave (reset by the observer at each wave start,
// when no simulation is in flight).
class CountingSimulator : public Simulator {
 public:
  int output_size() const override { return 4; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    calls++;
    ones += theta.bits[0];
    for (int k = 0; k < 4; ++k) out[k] = theta.bits[k];
  }
  mutable std::atomic<long> calls{0}, ones{0};
};

class ResetAtWave : public SmcObserver {
 public:
  explicit ResetAtWave(CountingSimulator& sim) : sim_(sim) {}
  void OnWaveStart(const WaveRecord&) override { sim_.calls = sim_.ones = 0; }

 private:
  CountingSimulator& sim_;
};

// Accepts only bit 0 = 0, so wave 0's accepted fraction p^ of bit 0 is exactly 0.
class BitZeroIsZero : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"bit0", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override { out[0] = y[0]; }
};

TEST(Tempering, StuckBitIsProposedAtTheRateEq3Predicts) {
  BinarySpaceOptions so;
  so.dimension = 4;
  so.default_prior_one = 0.3;
  const ParameterSpace space{BinarySpace(so)};
  BitZeroIsZero dist;
  struct Setting {
    TemperingForm form;
    double phi;
    double expected;  // P(bit 0 = 1) in wave 1 given p^ = 0 and prior 0.3
  };
  for (const auto& s : {Setting{TemperingForm::kGeometric, 1.0, 0.3},
                        Setting{TemperingForm::kGeometric, 0.5, 0.0},
                        Setting{TemperingForm::kMixture, 0.4, 0.12}}) {
    CountingSimulator sim;
    ResetAtWave reset(sim);
    SmcOptions o;
    o.num_waves = 2;
    o.accepted_per_wave = 4000;
    o.thresholds = {List({0, 0})};
    o.tempering.kind = TemperingKind::kList;
    o.tempering.form = s.form;
    o.tempering.values = {s.phi};
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o, &reset);
    ASSERT_EQ(h.waves.size(), 2u);
    EXPECT_EQ(h.waves[0].marginals_paper[0], 0.0);
    EXPECT_NEAR(h.waves[1].proposal[0], s.expected, 1e-15);
    const double rate = static_cast<double>(sim.ones) / static_cast<double>(sim.calls);
    // Binomial bound at 6 sigma over >= 4000 proposals.
    const double sd = std::sqrt(s.expected * (1 - s.expected) / static_cast<double>(sim.calls));
    EXPECT_NEAR(rate, s.expected, 6 * sd + 1e-12) << ToString(s.form) << " phi " << s.phi;
  }
}

}  // namespace
}  // namespace combabc
