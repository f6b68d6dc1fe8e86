// Same seed => bit-identical run history for any thread count, any batch size, and across a
// resume from any checkpoint (STYLE.md: determinism is a tested property).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "checkpoints.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "minor_modes.hpp"
#include "support/test_support.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

struct ToyRun {
  ParameterSpace space{BinarySpace::Independent(20, 0.4)};
  testing::NoisySimulator sim{20, 0.25};  // stochastic: draws from each candidate's stream
  testing::WeightedL1Distance dist{
      {1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1},
      {3, 3, 2, 2, 2, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0.5, 0.5, 0.5, 0, 0}};
  SmcOptions options(Estimator estimator, int threads) const {
    SmcOptions o;
    o.num_waves = 4;
    o.accepted_per_wave = 150;
    o.estimator = estimator;
    o.threads = threads;
    o.seed = 20240727;
    o.tempering.kind = TemperingKind::kLinear;
    o.tempering.phi0 = 0.3;
    return o;
  }
  RunHistory Run(const SmcOptions& o,
                 SmcObserver* obs = nullptr,
                 const ResumePoint* resume = nullptr) const {
    return RunCombinatorialSmc({&space, &sim, &dist}, o, obs, resume);
  }
};

TEST(Determinism, IdenticalHistoriesFor1_2_4_16Threads) {
  ToyRun s;
  for (auto estimator : {Estimator::kPaper, Estimator::kImportance}) {
    const auto reference = s.Run(s.options(estimator, 1));
    ASSERT_EQ(reference.waves.size(), 4u);
    for (int threads : {1, 2, 4, 16}) {
      const auto h = s.Run(s.options(estimator, threads));
      std::string where;
      EXPECT_TRUE(SameHistory(reference, h, &where))
          << ToString(estimator) << ", " << threads << " threads: " << where;
    }
  }
}

TEST(Determinism, BatchSizeDoesNotChangeTheHistory) {
  ToyRun s;
  auto o = s.options(Estimator::kImportance, 2);
  const auto reference = s.Run(o);
  for (int batch : {1, 7, 100, 5000}) {
    o.batch_size = batch;
    std::string where;
    EXPECT_TRUE(SameHistory(reference, s.Run(o), &where)) << "batch " << batch << ": " << where;
  }
}

// A simulator that takes at least `seconds` per call, like an external program.
class SlowSimulator : public testing::NoisySimulator {
 public:
  SlowSimulator(int d, double sigma, double seconds)
      : NoisySimulator(d, sigma), seconds_(seconds) {}
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds_));
    NoisySimulator::Simulate(theta, rng, out);
  }

 private:
  double seconds_;
};

// The automatic batch size follows the measured cost of a simulation (docs/algorithm.md, "Batch
// size"): timing changes how many candidates are simulated past a wave's last acceptance, never
// the history. With 10 ms simulations on 2 threads a batch is at least 2 x ceil(50 ms / cost) <= 10
// candidates (a loaded machine only makes the cost larger and the batches smaller), where it was
// at least 32 x 2 = 64 before: the overshoot stays far below that.
TEST(Determinism, AutomaticBatchesFollowTheSimulationCostAndLeaveTheHistoryAlone) {
  ToyRun s;
  const SlowSimulator slow(20, 0.25, 0.01);
  auto o = s.options(Estimator::kImportance, 2);
  o.num_waves = 3;
  o.accepted_per_wave = 12;
  const auto automatic = RunCombinatorialSmc({&s.space, &slow, &s.dist}, o);
  o.batch_size = 1;
  const auto one_by_one = s.Run(o);  // the fast simulator: the same draws, instantly
  std::string where;
  EXPECT_TRUE(SameHistory(one_by_one, automatic, &where)) << where;
  EXPECT_EQ(one_by_one.summary.simulations_discarded, 0);
  for (const WaveRecord& w : automatic.waves) {
    EXPECT_LT(w.discarded, 32) << "wave " << w.wave << " of " << w.candidates << " candidates";
  }
}

TEST(Determinism, DifferentSeedsGiveDifferentHistories) {
  ToyRun s;
  auto o = s.options(Estimator::kImportance, 1);
  const auto a = s.Run(o);
  o.seed += 1;
  EXPECT_FALSE(SameHistory(a, s.Run(o), nullptr));
}

using testing::Checkpoints;

TEST(Determinism, ResumingFromAnyCheckpointReproducesTheUninterruptedRun) {
  ToyRun s;
  auto o = s.options(Estimator::kImportance, 2);
  o.batch_size = 64;
  Checkpoints checkpoints;
  const auto reference = s.Run(o, &checkpoints);
  ASSERT_GT(checkpoints.points.size(), 8u);
  for (std::size_t i = 0; i < checkpoints.points.size(); i += 3) {
    auto resumed_options = o;
    resumed_options.threads = 1 + static_cast<int>(i % 4);  // a resume may use other threads
    resumed_options.batch_size = 0;
    const auto h = s.Run(resumed_options, nullptr, &checkpoints.points[i]);
    std::string where;
    EXPECT_TRUE(SameHistory(reference, h, &where)) << "checkpoint " << i << ": " << where;
  }
}

// The ancestor kernel draws each candidate's ancestor from the candidate's own stream: a mixed
// run's history is the same for any thread count and batch size, and across a resume.
TEST(Determinism, AncestorKernelHistoryIsIndependentOfThreadsBatchesAndResume) {
  namespace mm = testing::minor_modes;
  const ParameterSpace space = mm::Space();
  const mm::Simulator sim(mm::Variant::kJointFlips);
  const mm::Distance dist;
  auto o = mm::Options(BinaryKernelKind::kAncestor, ContinuousKernelKind::kNormal, 100, 5);
  o.threads = 1;
  o.batch_size = 32;
  Checkpoints checkpoints;
  const auto reference = RunCombinatorialSmc({&space, &sim, &dist}, o, &checkpoints);
  ASSERT_EQ(reference.waves.size(), mm::kEps1.size());
  for (const int threads : {2, 4}) {
    for (const int batch : {1, 100}) {
      auto other = o;
      other.threads = threads;
      other.batch_size = batch;
      std::string where;
      EXPECT_TRUE(SameHistory(reference, RunCombinatorialSmc({&space, &sim, &dist}, other), &where))
          << threads << " threads, batch " << batch << ": " << where;
    }
  }
  ASSERT_GT(checkpoints.points.size(), 4u);
  for (std::size_t i = 1; i < checkpoints.points.size(); i += testing::Stride(4)) {
    auto resumed = o;
    resumed.threads = 2;
    const auto h =
        RunCombinatorialSmc({&space, &sim, &dist}, resumed, nullptr, &checkpoints.points[i]);
    std::string where;
    EXPECT_TRUE(SameHistory(reference, h, &where)) << "checkpoint " << i << ": " << where;
  }
}

// The summary's overshoot count is part of the run's outcome: a resumed run must count the waves
// before the resume too (with a fixed batch_size its batches are the uninterrupted run's).
TEST(Determinism, ResumedRunCountsTheSameDiscardedSimulations) {
  ToyRun s;
  // A fixed batch size: automatic ones follow the measured simulation cost, hence the clock.
  auto o = s.options(Estimator::kPaper, 2);
  o.batch_size = 96;
  Checkpoints checkpoints;
  const auto reference = s.Run(o, &checkpoints);
  ASSERT_GT(reference.summary.simulations_discarded, 0) << "the toy run must overshoot";
  std::int64_t per_wave = 0;
  for (const auto& w : reference.waves) per_wave += w.discarded;
  EXPECT_EQ(per_wave, reference.summary.simulations_discarded);
  for (std::size_t i = 0; i < checkpoints.points.size(); ++i) {
    const auto h = s.Run(o, nullptr, &checkpoints.points[i]);
    EXPECT_EQ(h.summary.simulations_discarded, reference.summary.simulations_discarded)
        << "checkpoint " << i << " (" << checkpoints.points[i].completed.size()
        << " waves complete)";
  }
}

}  // namespace
}  // namespace combabc

namespace combabc {
namespace {

// A simulator with its own batch form (as a vectorising one would have): the engine must use it
// and get the same history as from the per-candidate form.
class BatchedNoisySimulator : public testing::NoisySimulator {
 public:
  using NoisySimulator::NoisySimulator;
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override {
    ++batches;
    NoisySimulator::SimulateBatch(batch, rngs, out, failures);
  }
  mutable std::atomic<int> batches{0};
};

TEST(Determinism, BatchFormGivesTheSameHistory) {
  ToyRun s;
  const auto o = s.options(Estimator::kImportance, 2);
  const auto reference = s.Run(o);
  BatchedNoisySimulator batched(20, 0.25);
  const auto h = RunCombinatorialSmc({&s.space, &batched, &s.dist}, o);
  EXPECT_GT(batched.batches.load(), 0);
  std::string where;
  EXPECT_TRUE(SameHistory(reference, h, &where)) << where;
}

TEST(Dimensions, RunsFromOneTo1024Bits) {
  for (int d : {1, 2, 1024}) {
    const ParameterSpace space(BinarySpace::Independent(d));
    testing::IdentitySimulator sim(d);
    // Only bit 0 matters: it must be 1. Every other bit is unidentifiable (posterior = prior).
    std::vector<double> target(static_cast<std::size_t>(d), 0.0), weights(target.size(), 0.0);
    target[0] = 1.0;
    weights[0] = 1.0;
    testing::WeightedL1Distance dist(target, weights);
    SmcOptions o;
    o.num_waves = 2;
    o.accepted_per_wave = 200;
    o.threads = 2;
    // The paper estimator: with 1023 unidentifiable bits the importance weights p/q are products
    // of 1023 ratios and degenerate (docs/algorithm.md, "High dimension").
    o.estimator = Estimator::kPaper;
    ThresholdSchedule eps;
    eps.kind = ThresholdKind::kList;
    eps.values = {0.0, 0.0};
    o.thresholds = {eps};
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached) << "d = " << d;
    const auto& m = h.waves.back().marginals_paper;
    ASSERT_EQ(m.size(), static_cast<std::size_t>(d));
    EXPECT_NEAR(m[0], 1.0, 1e-12) << "d = " << d;
    // Unidentifiable bits: two rounds of 200 Bernoulli draws (wave 0 sets the proposal, wave 1
    // samples it), so the variance is at most 2 x 0.25 / 200; 6 standard errors.
    for (int k = 1; k < d; ++k) {
      EXPECT_NEAR(m[k], 0.5, 6 * std::sqrt(2 * 0.25 / 200)) << "d = " << d << ", bit " << k;
    }
  }
}

}  // namespace
}  // namespace combabc
