// Resample-move runs keep every determinism promise of the rejection sampler: the same history
// for any thread count and batch size, and across a resume from any checkpoint (a move wave cut
// short is done again from its start); on a stochastic simulator (pseudo-marginal moves) and on a
// mixed space.
#include <gtest/gtest.h>

#include "checkpoints.hpp"
#include "combabc/core/error.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "minor_modes.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

struct NoisyToy {
  ParameterSpace space{BinarySpace::Independent(20, 0.4)};
  testing::NoisySimulator sim{20, 0.25};  // stochastic: draws from each candidate's stream
  testing::WeightedL1Distance dist{
      {1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1},
      {3, 3, 2, 2, 2, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0.5, 0.5, 0.5, 0, 0}};
  SmcOptions Options(int threads) const {
    SmcOptions o;
    o.method = SamplerMethod::kResampleMove;
    o.num_waves = 4;
    o.accepted_per_wave = 100;
    o.threads = threads;
    o.seed = 20261207;
    o.moves.max_rounds = 4;
    return o;
  }
  RunHistory Run(const SmcOptions& o,
                 SmcObserver* obs = nullptr,
                 const ResumePoint* resume = nullptr) const {
    return RunCombinatorialSmc({&space, &sim, &dist}, o, obs, resume);
  }
};

TEST(MoveDeterminism, ThreadsAndBatchSizesDoNotChangeTheHistory) {
  NoisyToy toy;
  const auto reference = toy.Run(toy.Options(1));
  ASSERT_EQ(reference.waves.size(), 4u);
  ASSERT_TRUE(reference.waves.back().moves.has_value());
  for (int threads : {2, 4}) {
    std::string where;
    EXPECT_TRUE(SameHistory(reference, toy.Run(toy.Options(threads)), &where))
        << threads << " threads: " << where;
  }
  for (int batch : {1, 7}) {
    auto o = toy.Options(2);
    o.batch_size = batch;
    std::string where;
    EXPECT_TRUE(SameHistory(reference, toy.Run(o), &where)) << "batch " << batch << ": " << where;
  }
  auto other = toy.Options(1);
  other.seed += 1;
  EXPECT_FALSE(SameHistory(reference, toy.Run(other), nullptr));
}

TEST(MoveDeterminism, ResumingFromAnyCheckpointReproducesTheUninterruptedRun) {
  NoisyToy toy;
  auto o = toy.Options(2);
  o.batch_size = 40;
  testing::Checkpoints checkpoints;
  const auto reference = toy.Run(o, &checkpoints);
  ASSERT_GT(checkpoints.points.size(), 10u);
  for (std::size_t i = 0; i < checkpoints.points.size(); i += 2) {
    auto resumed = o;
    resumed.threads = 1 + static_cast<int>(i % 3);
    resumed.batch_size = 0;
    // What a store keeps: ancestors, not Eves (AssignEveIndices derives them).
    ResumePoint point = checkpoints.points[i];
    for (auto& w : point.completed) {
      for (auto& p : w.particles) p.eve = -1;
    }
    const auto h = toy.Run(resumed, nullptr, &point);
    std::string where;
    EXPECT_TRUE(SameHistory(reference, h, &where)) << "checkpoint " << i << ": " << where;
    for (std::size_t t = 0; t < h.waves.size(); ++t) {
      for (std::size_t k = 0; k < h.waves[t].particles.size(); ++k) {
        ASSERT_EQ(h.waves[t].particles[k].eve, reference.waves[t].particles[k].eve)
            << "checkpoint " << i << ", wave " << t;
      }
    }
  }
}

TEST(MoveDeterminism, MixedSpaceIsIndependentOfThreads) {
  namespace mm = testing::minor_modes;
  const ParameterSpace space = mm::Space();
  const mm::Simulator sim(mm::Variant::kJointFlips);
  const mm::Distance dist;
  auto o = mm::Options(BinaryKernelKind::kIndependent, ContinuousKernelKind::kNormal, 100, 5);
  o.method = SamplerMethod::kResampleMove;
  o.moves.max_rounds = 3;
  o.threads = 1;
  const auto reference = RunCombinatorialSmc({&space, &sim, &dist}, o);
  ASSERT_TRUE(reference.waves.back().moves.has_value());
  o.threads = 3;
  std::string where;
  EXPECT_TRUE(SameHistory(reference, RunCombinatorialSmc({&space, &sim, &dist}, o), &where))
      << where;
}

// The final independent wave after the move wave that reaches the target: the same history for
// any thread count, and from any checkpoint, the one just before it included (a run resumed
// after its last move wave still draws it).
TEST(MoveDeterminism, FinalIndependentWaveResumesLikeTheUninterruptedRun) {
  // The noise-aware linear problem of move_exactness_test.cpp, whose final wave kAuto draws.
  const testing::LinearSimulator sim{{{1.0, 0.5, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0},
                                      {0.0, 1.0, 0.8, 0.0, 0.2, 0.0, 0.0, 0.0},
                                      {0.3, 0.0, 1.0, 0.1, 0.0, 0.6, 0.0, 0.0},
                                      {0.0, 0.0, 0.0, 0.1, 1.0, 0.4, 0.0, 0.0},
                                      {0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.2, 0.0},
                                      {0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.7, 0.7}}};
  const testing::GaussianNllDistance distance{{1.25, 0.7, 1.3, 0.2, 0.75, 0.6}, 0.3};
  const ParameterSpace space{BinarySpace::Independent(8, 0.5)};
  SmcOptions o;
  o.method = SamplerMethod::kResampleMove;
  o.moves.final_wave = FinalWave::kAuto;
  o.num_waves = 30;
  o.accepted_per_wave = 100;
  o.seed = 7;
  o.threads = 2;
  o.batch_size = 64;
  ThresholdSchedule s;
  s.target = 1;
  o.thresholds = {s};
  testing::Checkpoints checkpoints;
  const auto reference = RunCombinatorialSmc({&space, &sim, &distance}, o, &checkpoints);
  ASSERT_EQ(reference.summary.termination, Termination::kTargetReached);
  ASSERT_GE(reference.waves.size(), 3u);
  ASSERT_FALSE(reference.waves.back().moves.has_value());
  ASSERT_TRUE(reference.waves[reference.waves.size() - 2].moves.has_value());
  auto one = o;
  one.threads = 1;
  one.batch_size = 0;
  std::string where;
  EXPECT_TRUE(SameHistory(reference, RunCombinatorialSmc({&space, &sim, &distance}, one), &where))
      << where;
  // The checkpoint after the last move wave: every wave but the final one complete.
  bool before_final = false;
  for (std::size_t i = 0; i < checkpoints.points.size(); ++i) {
    const ResumePoint& point = checkpoints.points[i];
    before_final = before_final ||
                   (point.completed.size() + 1 == reference.waves.size() && !point.has_partial);
    if (i % 3 != 0 && point.completed.size() + 1 != reference.waves.size()) continue;
    const auto h = RunCombinatorialSmc({&space, &sim, &distance}, one, nullptr, &point);
    EXPECT_TRUE(SameHistory(reference, h, &where)) << "checkpoint " << i << ": " << where;
  }
  EXPECT_TRUE(before_final);
}

TEST(MoveDeterminism, PaperEstimatorIsRefused) {
  NoisyToy toy;
  auto o = toy.Options(1);
  o.estimator = Estimator::kPaper;
  EXPECT_THROW(toy.Run(o), Error);
}

}  // namespace
}  // namespace combabc
