// Failed simulations (SimulationFailed, NaN outputs, a candidate the distance cannot measure) are
// rejected candidates recorded with their reason, and a run with too many of them stops
// (docs/algorithm.md, "Failed simulations").
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/core/fnv1a.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

using testing::WeightedL1Distance;

constexpr int kBits = 8;

// A deterministic quarter or so of the configurations: FNV-1a of the bits, 0 mod 4.
bool Fails(std::span<const std::uint8_t> bits) { return Fnv1a(bits) % 4 == 0; }

enum class Mode {
  kThrow,   // SimulationFailed from Simulate
  kNan,     // NaN at output 3
  kFar,     // an output no threshold accepts: the "simply rejected" twin of the above
  kDefect,  // std::logic_error: a defect, fatal
};

// Output = the bits, except on the failing configurations.
class FlakySimulator : public Simulator {
 public:
  explicit FlakySimulator(Mode mode) : mode_(mode) {}
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
    if (!Fails(theta.bits)) return;
    switch (mode_) {
      case Mode::kThrow:
        throw SimulationFailed("solver diverged");
      case Mode::kNan:
        out[3] = std::numeric_limits<double>::quiet_NaN();
        return;
      case Mode::kFar:
        for (double& v : out) v = 5.0;
        return;
      case Mode::kDefect:
        throw std::logic_error("bug");
    }
  }

 private:
  Mode mode_;
};

// A vectorising simulator marks its failed candidates itself.
class BatchFlakySimulator : public FlakySimulator {
 public:
  BatchFlakySimulator() : FlakySimulator(Mode::kFar) {}
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override {
    for (std::size_t i = 0; i < batch.count; ++i) {
      if (Fails(batch[i].bits)) {
        failures.Fail(i, "solver diverged");
      } else {
        Simulate(batch[i], rngs[i], out.subspan(i * kBits, kBits));
      }
    }
  }
};

// A distance with its own batch form (as one written in Python has): it cannot measure the far
// outputs (5.0) and fails those candidates itself, and counts its calls.
class BatchFailingDistance : public WeightedL1Distance {
 public:
  using WeightedL1Distance::WeightedL1Distance;
  void EvaluateBatch(std::span<const double> simulated,
                     std::span<double> out,
                     BatchFailures& failures) const override {
    ++calls;
    for (std::size_t i = 0; i < failures.size(); ++i) {
      if (failures.failed(i)) continue;
      const auto output = simulated.subspan(i * kBits, kBits);
      if (output[0] == 5.0) {
        failures.Fail(i, "cannot measure");
      } else {
        Evaluate(output, out.subspan(i, 1));
      }
    }
  }
  mutable std::atomic<int> calls{0};
};

ThresholdSchedule List(std::vector<double> values) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kList;
  s.values = std::move(values);
  return s;
}

struct Toy {
  ParameterSpace space{BinarySpace::Independent(kBits)};
  WeightedL1Distance dist{{1, 0, 1, 0, 1, 0, 1, 0}, {1, 1, 1, 1, 1, 1, 1, 1}};
  SmcOptions options(int threads) const {
    SmcOptions o;
    o.num_waves = 3;
    o.accepted_per_wave = 60;
    o.thresholds = {List({4, 2, 1})};  // finite: a far (5.0) output is never accepted
    o.threads = threads;
    o.seed = 77;
    o.batch_size = threads == 1 ? 0 : 37;
    o.max_failure_fraction = 1.0;  // about a quarter fail; this test is not about the ceiling
    return o;
  }
  RunHistory Run(const Simulator& sim,
                 const SmcOptions& o,
                 SmcObserver* observer = nullptr,
                 const ResumePoint* resume = nullptr) const {
    return RunCombinatorialSmc({&space, &sim, &dist}, o, observer, resume);
  }
};

// The history with failures removed: what a run where they were simply rejected records.
RunHistory WithoutFailures(RunHistory h) {
  for (auto& w : h.waves) w.failures.clear();
  return h;
}

TEST(Failures, AreRejectedCandidatesRecordedWithTheirReason) {
  Toy toy;
  const FlakySimulator flaky(Mode::kThrow), far(Mode::kFar);
  const RunHistory h = toy.Run(flaky, toy.options(1));
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached) << h.summary.message;
  std::int64_t failures = 0;
  for (const auto& w : h.waves) {
    EXPECT_GT(w.failures.size(), 0u) << "wave " << w.wave;
    for (std::size_t i = 0; i < w.failures.size(); ++i) {
      EXPECT_EQ(w.failures[i].reason, "solver diverged");
      EXPECT_LT(w.failures[i].index, w.candidates);
      if (i > 0) {
        EXPECT_LT(w.failures[i - 1].index, w.failures[i].index);
      }
    }
    for (const auto& p : w.particles) EXPECT_FALSE(Fails(p.theta.bits));
    failures += static_cast<std::int64_t>(w.failures.size());
  }
  EXPECT_EQ(h.summary.failures, failures);
  EXPECT_NE(h.summary.BriefReport().find(std::to_string(failures) + " failed"), std::string::npos);
  // Exactly the run in which those candidates were simulated and rejected.
  std::string where;
  EXPECT_TRUE(SameHistory(WithoutFailures(h), toy.Run(far, toy.options(1)), &where)) << where;
}

TEST(Failures, TheSameFor1And2ThreadsAndForABatchSimulator) {
  Toy toy;
  const FlakySimulator flaky(Mode::kThrow);
  const BatchFlakySimulator batch;
  const RunHistory one = toy.Run(flaky, toy.options(1));
  std::string where;
  EXPECT_TRUE(SameHistory(one, toy.Run(flaky, toy.options(2)), &where)) << where;
  EXPECT_TRUE(SameHistory(one, toy.Run(batch, toy.options(2)), &where)) << where;
}

TEST(Failures, ANanOutputIsAFailedSimulation) {
  Toy toy;
  const FlakySimulator nan(Mode::kNan), far(Mode::kFar);
  const RunHistory h = toy.Run(nan, toy.options(2));
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached) << h.summary.message;
  ASSERT_FALSE(h.waves[0].failures.empty());
  EXPECT_EQ(h.waves[0].failures[0].reason, "output holds NaN at index 3");
  std::string where;
  EXPECT_TRUE(SameHistory(WithoutFailures(h), toy.Run(far, toy.options(1)), &where)) << where;
}

TEST(Failures, ADistanceFailsTheCandidatesItCannotMeasureInItsBatchCall) {
  Toy toy;
  const FlakySimulator far(Mode::kFar);
  const BatchFailingDistance failing({1, 0, 1, 0, 1, 0, 1, 0}, {1, 1, 1, 1, 1, 1, 1, 1});
  const RunHistory h =
      RunCombinatorialSmc({&toy.space, &far, &failing}, toy.options(2), nullptr, nullptr);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached) << h.summary.message;
  ASSERT_FALSE(h.waves[0].failures.empty());
  for (const auto& w : h.waves) {
    for (const auto& f : w.failures) EXPECT_EQ(f.reason, "cannot measure");
  }
  // One call per range of a batch (4 or more candidates here), not one per candidate.
  EXPECT_LT(failing.calls.load(), h.summary.simulations / 2);
  std::string where;
  EXPECT_TRUE(SameHistory(WithoutFailures(h), toy.Run(far, toy.options(1)), &where)) << where;
}

TEST(Failures, AnyOtherExceptionEndsTheRun) {
  Toy toy;
  const FlakySimulator defect(Mode::kDefect);
  try {
    toy.Run(defect, toy.options(1));
    FAIL() << "a defect must end the run";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kSoftware);
    EXPECT_NE(std::string(e.what()).find("bug"), std::string::npos) << e.what();
  }
}

TEST(Failures, TooManyStopTheRunAtTheSameCandidateForAnyThreads) {
  Toy toy;
  const FlakySimulator flaky(Mode::kThrow);
  auto o = toy.options(1);
  o.max_failure_fraction = 0.1;  // the default; about a quarter fail
  const RunHistory h = toy.Run(flaky, o);
  ASSERT_EQ(h.summary.termination, Termination::kTooManyFailures) << h.summary.message;
  EXPECT_GE(h.summary.simulations, o.failure_fraction_after);
  EXPECT_GT(static_cast<double>(h.summary.failures),
            0.1 * static_cast<double>(h.summary.simulations));
  // Judged candidate by candidate: it stops on the first candidate past the after-count.
  EXPECT_EQ(h.summary.simulations, o.failure_fraction_after);
  const std::string& m = h.summary.message;
  EXPECT_NE(m.find(std::to_string(h.summary.failures) + " of " +
                   std::to_string(h.summary.simulations) + " simulations failed"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("> 10 %); last failure: wave 1, candidate "), std::string::npos) << m;
  EXPECT_NE(m.find(": solver diverged"), std::string::npos) << m;
  EXPECT_FALSE(h.waves.back().complete);
  auto two = o;
  two.threads = 2;
  two.batch_size = 13;
  std::string where;
  EXPECT_TRUE(SameHistory(h, toy.Run(flaky, two), &where)) << where;
  EXPECT_EQ(toy.Run(flaky, two).summary.message, m);
}

// Records a resume point at every checkpoint, failures included (as the SQLite history does).
class Checkpoints : public SmcObserver {
 public:
  void OnWaveStart(const WaveRecord& w) override {
    accepted_.clear();
    failed_.clear();
    wave_ = w.wave;
  }
  void OnBatch(const BatchProgress& p, std::span<const Particle> accepted) override {
    accepted_.insert(accepted_.end(), accepted.begin(), accepted.end());
    failed_.insert(failed_.end(), p.failed.begin(), p.failed.end());
    EXPECT_EQ(p.failures, static_cast<std::int64_t>(failed_.size()));
    ResumePoint r;
    r.completed = completed_;
    r.has_partial = true;
    r.partial_wave = wave_;
    r.partial_next_index = p.next_index;
    r.partial_accepted = accepted_;
    r.partial_discarded = p.discarded;
    r.partial_failures = failed_;
    points.push_back(std::move(r));
  }
  void OnWaveEnd(const WaveRecord& w) override {
    if (w.complete) completed_.push_back(w);
  }
  std::vector<ResumePoint> points;

 private:
  int wave_ = 0;
  std::vector<Particle> accepted_;
  std::vector<SimulationFailure> failed_;
  std::vector<WaveRecord> completed_;
};

TEST(Failures, AResumedRunGivesTheSameHistory) {
  Toy toy;
  const FlakySimulator flaky(Mode::kThrow);
  auto o = toy.options(2);
  o.batch_size = 25;
  Checkpoints checkpoints;
  const RunHistory reference = toy.Run(flaky, o, &checkpoints);
  ASSERT_GT(checkpoints.points.size(), 6u);
  for (std::size_t i = 0; i < checkpoints.points.size(); i += 2) {
    const RunHistory h = toy.Run(flaky, toy.options(1), nullptr, &checkpoints.points[i]);
    std::string where;
    EXPECT_TRUE(SameHistory(reference, h, &where)) << "checkpoint " << i << ": " << where;
    EXPECT_EQ(h.summary.failures, reference.summary.failures) << "checkpoint " << i;
  }
}

}  // namespace
}  // namespace combabc
