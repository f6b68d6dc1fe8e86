// Same seed => bit-identical run history for any thread count, any batch size, and across a
// resume from any checkpoint (STYLE.md: determinism is a tested property).
#include <gtest/gtest.h>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

struct ToyRun {
  BinarySpace space = BinarySpace::Independent(20, 0.4);
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

TEST(Determinism, DifferentSeedsGiveDifferentHistories) {
  ToyRun s;
  auto o = s.options(Estimator::kImportance, 1);
  const auto a = s.Run(o);
  o.seed += 1;
  EXPECT_FALSE(SameHistory(a, s.Run(o), nullptr));
}

// Records the run's state at every checkpoint, as the SQLite history does.
class Checkpoints : public SmcObserver {
 public:
  void OnWaveStart(const WaveRecord& w) override { current_.clear(), wave_ = w.wave; }
  void OnBatch(const BatchProgress& p, std::span<const Particle> accepted) override {
    current_.insert(current_.end(), accepted.begin(), accepted.end());
    ResumePoint r;
    r.completed = completed_;
    r.has_partial = true;
    r.partial_wave = wave_;
    r.partial_next_index = p.next_index;
    r.partial_accepted = current_;
    points.push_back(std::move(r));
  }
  void OnWaveEnd(const WaveRecord& w) override {
    if (w.complete) completed_.push_back(w);
  }
  std::vector<ResumePoint> points;

 private:
  int wave_ = 0;
  std::vector<Particle> current_;
  std::vector<WaveRecord> completed_;
};

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

}  // namespace
}  // namespace combabc
