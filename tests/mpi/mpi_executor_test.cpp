// MpiExecutor under `mpiexec -np 3` (tests/mpi/CMakeLists.txt): every rank runs these tests in
// step, as the sampler would. A toy task whose rows are a function of the candidate index checks
// that every rank ends with every row whatever the slicing, that a failure on one rank is thrown
// on all with the same message, and that decisions are the primary's.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <stdexcept>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/core/fnv1a.hpp"
#include "combabc/mpi/mpi_executor.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"

namespace combabc::mpi {
namespace {

// Two buffers of different widths; row i holds values derived from i. Candidate `fail_at` throws.
class ToyTask : public BatchTask {
 public:
  explicit ToyTask(std::size_t n, std::size_t fail_at = SIZE_MAX)
      : a_(n * 3, 0.0), b_(n, 0), fail_at_(fail_at) {}
  void EvaluateRange(std::size_t begin, std::size_t end) override {
    for (std::size_t i = begin; i < end; ++i) {
      if (i == fail_at_) {
        throw Error(ErrorKind::kSoftware, "candidate " + std::to_string(i), "sim.toml", 7, "x");
      }
      for (std::size_t k = 0; k < 3; ++k) {
        a_[i * 3 + k] = static_cast<double>(i) + 0.25 * static_cast<double>(k);
      }
      b_[i] = static_cast<std::uint8_t>(i % 251);
      ++evaluated_;
    }
  }
  std::vector<Buffer> Results() override {
    return {{a_.data(), 3 * sizeof(double)}, {b_.data(), 1}};
  }
  std::vector<double> a_;
  std::vector<std::uint8_t> b_;
  std::size_t fail_at_;
  std::atomic<std::size_t> evaluated_{0};
};

TEST(MpiExecutor, EveryRankHoldsEveryRowForAnyBatchSize) {
  for (int threads : {1, 2}) {
    MpiExecutor executor(threads);
    ASSERT_EQ(executor.size(), 3) << "run under mpiexec -np 3";
    EXPECT_EQ(executor.concurrency(), 3 * threads);
    for (std::size_t n : {0, 1, 2, 3, 5, 100}) {
      ToyTask task(n);
      executor.Execute(n, task);
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
          EXPECT_EQ(task.a_[i * 3 + k], static_cast<double>(i) + 0.25 * static_cast<double>(k))
              << n << " " << i;
        }
        EXPECT_EQ(task.b_[i], i % 251) << n << " " << i;
      }
      // Each rank evaluated its slice only: about n / 3, not n.
      EXPECT_LE(task.evaluated_, n / 3 + 1) << n;
    }
  }
}

TEST(MpiExecutor, AFailureOnOneRankIsThrownOnEveryRankAlike) {
  MpiExecutor executor(1);
  // Candidate 7 of 9 lies in rank 2's slice [6, 9): ranks 0 and 1 succeed and must still throw.
  ToyTask task(9, 7);
  try {
    executor.Execute(9, task);
    FAIL() << "no exception on rank " << executor.rank();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kSoftware);
    EXPECT_EQ(e.message(), "candidate 7");
    EXPECT_EQ(e.file(), "sim.toml");
    EXPECT_EQ(e.line(), 7);
    EXPECT_EQ(e.field(), "x");
  }
  // Still in step afterwards.
  ToyTask ok(4);
  executor.Execute(4, ok);
  EXPECT_EQ(ok.a_[9], 3.0);  // row 3, first value
}

TEST(MpiExecutor, JoinThrowsTheLowestFailingRanksErrorEverywhere) {
  MpiExecutor executor(1);
  EXPECT_NO_THROW(executor.Join(nullptr));
  std::exception_ptr error;
  if (executor.rank() >= 1) {
    error = std::make_exception_ptr(std::runtime_error("rank " + std::to_string(executor.rank())));
  }
  try {
    executor.Join(error);
    FAIL() << "no exception on rank " << executor.rank();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "rank 1");
  }
}

// Fails on a deterministic subset of configurations: a rank that simulates a failed candidate
// must hand its status and reason to every rank with the other result rows.
class FlakySimulator : public Simulator {
 public:
  int output_size() const override { return 6; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    const std::uint64_t h = Fnv1a(theta.bits);
    if (h % 4 == 0) throw SimulationFailed("no convergence (" + std::to_string(h % 1000) + ")");
    for (std::size_t k = 0; k < 6; ++k) out[k] = theta.bits[k];
  }
};

class L1 : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"l1", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = 0;
    for (std::size_t k = 0; k < 6; ++k) out[0] += std::abs(y[k] - static_cast<double>(k % 2));
  }
};

TEST(MpiExecutor, FailedSimulationsAreGatheredLikeAnyResult) {
  const ParameterSpace space(BinarySpace::Independent(6));
  const FlakySimulator simulator;
  const L1 distance;
  SmcOptions o;
  o.num_waves = 2;
  o.accepted_per_wave = 40;
  o.batch_size = 17;
  o.max_failure_fraction = 1.0;
  ThresholdSchedule list;
  list.kind = ThresholdKind::kList;
  list.values = {3.0, 1.0};
  o.thresholds = {list};
  ThreadPoolExecutor local(1);
  const RunHistory reference =
      RunCombinatorialSmc({&space, &simulator, &distance, nullptr, &local}, o);
  MpiExecutor executor(1);
  const RunHistory h = RunCombinatorialSmc({&space, &simulator, &distance, nullptr, &executor}, o);
  ASSERT_GT(reference.summary.failures, 0);
  std::string where;
  EXPECT_TRUE(SameHistory(reference, h, &where)) << where;
}

// Resample-move waves (docs/algorithm.md, "Resample-move") on 3 ranks: the same history as one
// thread, failed simulations (rejected moves) included.
TEST(MpiExecutor, ResampleMoveHistoryIsTheThreadPools) {
  const ParameterSpace space(BinarySpace::Independent(6));
  const FlakySimulator simulator;
  const L1 distance;
  SmcOptions o;
  o.method = SamplerMethod::kResampleMove;
  o.num_waves = 4;
  o.accepted_per_wave = 40;
  o.batch_size = 13;
  o.max_failure_fraction = 1.0;
  o.moves.max_rounds = 3;
  ThresholdSchedule adaptive;
  adaptive.target = 1.0;
  o.thresholds = {adaptive};
  ThreadPoolExecutor local(1);
  const RunHistory reference =
      RunCombinatorialSmc({&space, &simulator, &distance, nullptr, &local}, o);
  ASSERT_TRUE(reference.waves.back().moves.has_value());
  MpiExecutor executor(1);
  const RunHistory h = RunCombinatorialSmc({&space, &simulator, &distance, nullptr, &executor}, o);
  std::string where;
  EXPECT_TRUE(SameHistory(reference, h, &where)) << where;
}

TEST(MpiExecutor, DecisionsAreThePrimarys) {
  MpiExecutor executor(1);
  EXPECT_EQ(executor.primary(), executor.rank() == 0);
  EXPECT_EQ(executor.FromPrimary(executor.rank() == 0), true);
  EXPECT_EQ(executor.FromPrimary(executor.rank() != 0), false);
  // A number (the measured simulation cost that sizes the batches): the primary's, exactly.
  EXPECT_EQ(executor.FromPrimary(0.125 + executor.rank()), 0.125);
  EXPECT_EQ(ExitCodeOfPrimary(executor.rank() == 0 ? 73 : 0), 73);
}

}  // namespace
}  // namespace combabc::mpi

int main(int argc, char** argv) {
  combabc::mpi::MpiSession session(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  // Every rank reports (a failure names its rank's output); any failing rank fails mpiexec.
  return RUN_ALL_TESTS();
}
