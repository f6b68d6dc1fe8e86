// Failed simulations in the SQLite history (schema v4): recorded batch by batch, read back, and
// kept identical across an interruption and a resume.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "combabc/core/fnv1a.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;
using testing::TempFolder;

constexpr int kBits = 8;

// Fails on a deterministic subset of configurations (FNV-1a of the bits, 0 mod 4).
class FlakySimulator : public Simulator {
 public:
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    const std::uint64_t h = Fnv1a(theta.bits);
    if (h % 4 == 0) throw SimulationFailed("exit status 3 (\"quoted\", 'single'; ümlaut)");
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
  }
};

class L1Distance : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"l1", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = 0;
    for (int k = 0; k < kBits; ++k) out[0] += std::abs(y[k] - (k % 2 == 0 ? 1.0 : 0.0));
  }
};

// Forwards to the history and asks to stop after `batches` batches (a killed run, as far as the
// history can tell: its last committed batch is where the resume continues).
class StopAfter : public SmcObserver {
 public:
  StopAfter(HistoryStore& store, int batches) : store_(store), left_(batches) {}
  void OnWaveStart(const WaveRecord& w) override { store_.OnWaveStart(w); }
  void OnBatch(const BatchProgress& p, std::span<const Particle> accepted) override {
    store_.OnBatch(p, accepted);
    --left_;
  }
  void OnWaveEnd(const WaveRecord& w) override { store_.OnWaveEnd(w); }
  bool ShouldStop() override { return left_ <= 0; }

 private:
  HistoryStore& store_;
  int left_;
};

class HistoryFailures : public ::testing::Test {
 protected:
  RunMetadata Metadata() const {
    RunMetadata m;
    m.config_text = "# failures test\n";
    m.seed = options_.seed;
    m.estimator = "importance";
    m.dimension = kBits;
    m.distance_components = distance_.components();
    for (int k = 0; k < kBits; ++k) m.output_positions.push_back(0.01 * k);
    return m;
  }
  SmcOptions Options(int threads) const {
    SmcOptions o;
    o.num_waves = 3;
    o.accepted_per_wave = 60;
    o.seed = 5;
    o.threads = threads;
    o.batch_size = 20;
    o.max_failure_fraction = 1.0;  // about a quarter fail
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = {4.0, 2.0, 1.0};
    o.thresholds = {s};
    return o;
  }
  RunHistory Run(const SmcOptions& o, SmcObserver* observer, const ResumePoint* resume) const {
    return RunCombinatorialSmc({&space_, &simulator_, &distance_}, o, observer, resume);
  }
  std::string Path(const char* name) const { return dir_ / name; }

  const TempFolder dir_{"failures-test"};
  ParameterSpace space_{BinarySpace::Independent(kBits)};
  FlakySimulator simulator_;
  L1Distance distance_;
  SmcOptions options_ = Options(1);
};

std::int64_t CountRows(const std::string& path, const char* sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql, -1, &s, nullptr), SQLITE_OK);
  std::int64_t n = -1;
  if (sqlite3_step(s) == SQLITE_ROW) n = sqlite3_column_int64(s, 0);
  sqlite3_finalize(s);
  sqlite3_close(db);
  return n;
}

TEST_F(HistoryFailures, AreRecordedAndReadBack) {
  const std::string path = Path("run.sqlite");
  RunHistory run;
  {
    HistoryStore store = HistoryStore::Create(path, Metadata());
    run = Run(options_, &store, nullptr);
    store.Finish(run.summary);
  }
  ASSERT_EQ(run.summary.termination, Termination::kTargetReached) << run.summary.message;
  ASSERT_GT(run.summary.failures, 0);
  EXPECT_EQ(CountRows(path, "SELECT count(*) FROM failure"), run.summary.failures);
  EXPECT_EQ(CountRows(path,
                      "SELECT count(*) FROM failure WHERE reason = "
                      "'exit status 3 (\"quoted\", ''single''; ümlaut)'"),
            run.summary.failures);
  EXPECT_EQ(CountRows(path, "SELECT sum(failures) FROM wave"), run.summary.failures);
  const RunHistory loaded = HistoryStore::Open(path, true).LoadHistory();
  std::string where;
  EXPECT_TRUE(SameHistory(run, loaded, &where)) << where;
  EXPECT_EQ(loaded.summary.failures, run.summary.failures);
  EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
}

TEST_F(HistoryFailures, AResumedRunGivesTheSameHistory) {
  const std::string whole = Path("whole.sqlite");
  {
    HistoryStore store = HistoryStore::Create(whole, Metadata());
    store.Finish(Run(options_, &store, nullptr).summary);
  }
  const RunHistory reference = HistoryStore::Open(whole, true).LoadHistory();
  for (int batches : {2, 5, 8}) {
    const std::string path = Path(("cut" + std::to_string(batches) + ".sqlite").c_str());
    {
      HistoryStore store = HistoryStore::Create(path, Metadata());
      StopAfter stop(store, batches);
      const RunHistory cut = Run(options_, &stop, nullptr);
      ASSERT_EQ(cut.summary.termination, Termination::kInterrupted);
      store.Finish(cut.summary);
    }
    {
      HistoryStore store = HistoryStore::Open(path);
      const ResumePoint point = store.BeginResume();
      store.Finish(Run(Options(2), &store, &point).summary);
    }
    const RunHistory resumed = HistoryStore::Open(path, true).LoadHistory();
    std::string where;
    EXPECT_TRUE(SameHistory(reference, resumed, &where)) << batches << " batches: " << where;
    EXPECT_EQ(resumed.summary.failures, reference.summary.failures);
    EXPECT_EQ(CountRows(path, "SELECT count(*) FROM failure"), reference.summary.failures);
    EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
  }
}

TEST_F(HistoryFailures, AFailureRowChangedIsCaughtByTheChecksum) {
  const std::string path = Path("run.sqlite");
  {
    HistoryStore store = HistoryStore::Create(path, Metadata());
    store.Finish(Run(options_, &store, nullptr).summary);
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "UPDATE failure SET reason = 'tampered' WHERE rowid = "
                         "(SELECT min(rowid) FROM failure)",
                         nullptr,
                         nullptr,
                         nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  EXPECT_FALSE(HistoryStore::Verify(path).problems.empty());
}

}  // namespace
}  // namespace combabc
