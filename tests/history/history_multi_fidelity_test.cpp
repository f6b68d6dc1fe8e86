// A multi-fidelity run in its history (schema v7): the engine's run stored through the observer
// and reloaded, a partial wave's checkpoint as the resume point, and the checks of the new columns.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "history/fake_run.hpp"
#include "history/history_sqlite.hpp"
#include "history/sql_test_support.hpp"
#include "samplers/toy_models.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;
using testing::Sql;
using testing::TempFolder;

constexpr int kBits = 6;

// Output = the bits; the cheap model reports bit 1 inverted: it is wrong there.
class BitsSimulator : public Simulator {
 public:
  explicit BitsSimulator(bool wrong) : wrong_(wrong) {}
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta,
                RandomStream& /*rng*/,
                std::span<double> out) const override {
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
    if (wrong_) out[1] = 1.0 - out[1];
  }

 private:
  bool wrong_;
};

// Fills WaveRecord::multi_fidelity and BatchProgress::fidelity where the engine leaves them empty
// (deterministic stand-ins: the wave's confirmed particles as its expensive simulations, costs in
// proportion), so that the store's round trip is tested whichever part of the engine fills them.
class FillFidelity : public SmcObserver {
 public:
  FillFidelity(SmcObserver& store, const MultiFidelityOptions& options)
      : store_(store), options_(options) {}

  void Fill(WaveRecord& wave) const {
    if (wave.multi_fidelity) return;
    WaveFidelity f = Etas();
    for (const Particle& p : wave.particles) f.expensive_simulations += p.confirmed ? 1 : 0;
    f.cheap_seconds = 1e-3 * static_cast<double>(wave.candidates);
    f.expensive_seconds = 5e-3 * static_cast<double>(f.expensive_simulations);
    f.next_continue_if_accepted = options_.continue_if_accepted;
    f.next_continue_if_rejected = options_.continue_if_rejected;
    f.cost_ratio = 5.0;
    wave.multi_fidelity = f;
  }
  void OnWaveStart(const WaveRecord& wave) override {
    confirmed_ = 0;
    WaveRecord filled = wave;
    if (!filled.multi_fidelity) filled.multi_fidelity = Etas();
    store_.OnWaveStart(filled);
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    for (const Particle& p : accepted) confirmed_ += p.confirmed ? 1 : 0;
    BatchProgress filled = progress;
    if (!filled.fidelity) {
      WaveFidelity f = Etas();
      f.expensive_simulations = confirmed_;
      f.cheap_seconds = 1e-3 * static_cast<double>(progress.next_index);
      f.expensive_seconds = 5e-3 * static_cast<double>(confirmed_);
      filled.fidelity = f;
    }
    store_.OnBatch(filled, accepted);
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    WaveRecord filled = wave;
    Fill(filled);
    store_.OnWaveEnd(filled);
  }

 private:
  WaveFidelity Etas() const {
    WaveFidelity f;
    f.continue_if_accepted = options_.continue_if_accepted;
    f.continue_if_rejected = options_.continue_if_rejected;
    return f;
  }
  SmcObserver& store_;
  MultiFidelityOptions options_;
  std::int64_t confirmed_ = 0;
};

// The deterministic parts of a wave's multi-fidelity record (not its call times).
void ExpectSameFidelity(const std::optional<WaveFidelity>& a,
                        const std::optional<WaveFidelity>& b,
                        bool ended) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  EXPECT_EQ(a->continue_if_accepted, b->continue_if_accepted);
  EXPECT_EQ(a->continue_if_rejected, b->continue_if_rejected);
  EXPECT_EQ(a->expensive_simulations, b->expensive_simulations);
  if (!ended) return;
  EXPECT_EQ(a->next_continue_if_accepted, b->next_continue_if_accepted);
  EXPECT_EQ(a->next_continue_if_rejected, b->next_continue_if_rejected);
  EXPECT_EQ(a->cost_ratio, b->cost_ratio);
}

// SameHistory, and the multi-fidelity fields it does not compare.
void ExpectSameMultiFidelityHistory(const RunHistory& expected, const RunHistory& actual) {
  std::string where;
  EXPECT_TRUE(SameHistory(expected, actual, &where)) << where;
  ASSERT_EQ(expected.waves.size(), actual.waves.size());
  for (std::size_t t = 0; t < expected.waves.size(); ++t) {
    SCOPED_TRACE("wave " + std::to_string(t + 1));
    const WaveRecord& x = expected.waves[t];
    const WaveRecord& y = actual.waves[t];
    ExpectSameFidelity(x.multi_fidelity, y.multi_fidelity, /*ended=*/true);
    ASSERT_TRUE(y.multi_fidelity.has_value());
    EXPECT_EQ(x.multi_fidelity->cheap_seconds, y.multi_fidelity->cheap_seconds);
    EXPECT_EQ(x.multi_fidelity->expensive_seconds, y.multi_fidelity->expensive_seconds);
    ASSERT_EQ(x.particles.size(), y.particles.size());
    for (std::size_t i = 0; i < x.particles.size(); ++i) {
      EXPECT_EQ(x.particles[i].multiplier, y.particles[i].multiplier) << "particle " << i;
      EXPECT_EQ(x.particles[i].confirmed, y.particles[i].confirmed) << "particle " << i;
      EXPECT_EQ(x.particles[i].low_distance, y.particles[i].low_distance) << "particle " << i;
    }
  }
}

class HistoryMultiFidelityTest : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return folder_.path() / name; }

  // A small multi-fidelity run of the engine, stored as the CLI stores it; returns what it ran.
  RunHistory RunAndStore(const std::string& path) {
    const BitsSimulator expensive(false);
    const BitsSimulator cheap(true);
    const testing::WeightedL1Distance distance({1, 0, 1, 1, 0, 0}, {2, 2, 1, 1, 1, 0});
    BinarySpaceOptions space_options;
    space_options.dimension = kBits;
    const ParameterSpace space{BinarySpace(space_options)};
    SmcProblem problem{&space, &expensive, &distance};
    problem.low_fidelity = &cheap;
    SmcOptions options;
    options.num_waves = 3;
    options.accepted_per_wave = 150;
    options.batch_size = 40;
    options.seed = 24;
    options.threads = 1;
    options.keep_outputs = false;
    ThresholdSchedule schedule;
    schedule.kind = ThresholdKind::kList;
    schedule.values = {6, 3, 2};
    options.thresholds = {schedule};
    // eta_1 < 1: some cheap acceptances the expensive model rejects weigh 1 - 1/eta_1 < 0.
    options.multi_fidelity.continue_if_accepted = 0.5;
    options.multi_fidelity.continue_if_rejected = 0.3;
    options.multi_fidelity.adapt = false;

    RunMetadata metadata;
    metadata.dimension = kBits;
    metadata.estimator = "importance";
    metadata.distance_components = distance.components();
    HistoryStore store = HistoryStore::Create(path, metadata);
    FillFidelity observer(store, options.multi_fidelity);
    options.estimator = Estimator::kImportance;
    RunHistory history = RunCombinatorialSmc(problem, options, &observer);
    for (WaveRecord& wave : history.waves) observer.Fill(wave);
    store.Finish(history.summary);
    return history;
  }

  const TempFolder folder_{"history-mf-test"};
};

TEST_F(HistoryMultiFidelityTest, AnEngineRunRoundTripsThroughTheStore) {
  const std::string path = Path("RUN.db");
  const RunHistory ran = RunAndStore(path);
  ASSERT_EQ(ran.waves.size(), 3u);
  int negative = 0;
  int confirmed = 0;
  for (const WaveRecord& wave : ran.waves) {
    for (const Particle& p : wave.particles) {
      negative += p.multiplier < 0 ? 1 : 0;
      confirmed += p.confirmed ? 1 : 0;
      ASSERT_EQ(p.low_distance.size(), 1u);
    }
  }
  EXPECT_GT(negative, 0) << "the run should exercise negative multipliers";
  EXPECT_GT(confirmed, 0);

  const HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
  ExpectSameMultiFidelityHistory(ran, store.LoadHistory());
  const HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
  EXPECT_EQ(check.schema_version, kHistorySchemaVersion);
  // A finished run has no partial wave: its resume point holds every wave, etas included.
  const ResumePoint point = store.LoadResumePoint();
  EXPECT_FALSE(point.has_partial);
  EXPECT_FALSE(point.partial_fidelity.has_value());
  ASSERT_EQ(point.completed.size(), 3u);
  ExpectSameFidelity(
      ran.waves.back().multi_fidelity, point.completed.back().multi_fidelity, /*ended=*/true);
}

TEST_F(HistoryMultiFidelityTest, APartialWaveResumesWithItsEtasAndCostsSoFar) {
  testing::FakeRunOptions options;
  options.waves = 2;
  options.per_wave = 30;
  options.dimension = 10;
  options.points = 8;
  options.multi_fidelity = true;
  const RunHistory history = testing::MakeFakeHistory(options);
  ASSERT_EQ(history.waves.size(), 2u);
  const std::string path = Path("killed.db");
  constexpr std::int64_t kBatch = 7;
  {
    HistoryStore store = HistoryStore::Create(path, testing::MakeFakeMetadata(options));
    testing::RecordWave(store, history.waves[0], kBatch);
    testing::RecordWave(store, history.waves[1], kBatch, /*stop_after_batches=*/2);
  }
  // What the second batch of wave 2 recorded (RecordWave's costs in proportion).
  const WaveRecord& cut = history.waves[1];
  std::int64_t confirmed = 0;
  for (const Particle& p : cut.particles) confirmed += p.index < 2 * kBatch && p.confirmed ? 1 : 0;
  const double done = 2.0 * kBatch / static_cast<double>(cut.candidates);
  const auto check_point = [&](const ResumePoint& point) {
    ASSERT_TRUE(point.has_partial);
    EXPECT_EQ(point.partial_next_index, 2 * kBatch);
    ASSERT_TRUE(point.partial_fidelity.has_value());
    const WaveFidelity& f = *point.partial_fidelity;
    EXPECT_EQ(f.continue_if_accepted, testing::kFakeContinueIfAccepted);
    EXPECT_EQ(f.continue_if_rejected, testing::kFakeContinueIfRejected);
    EXPECT_EQ(
        f.expensive_simulations,
        std::max(confirmed,
                 static_cast<std::int64_t>(std::ceil(
                     done * static_cast<double>(cut.multi_fidelity->expensive_simulations)))));
    EXPECT_DOUBLE_EQ(f.cheap_seconds, done * cut.multi_fidelity->cheap_seconds);
    EXPECT_DOUBLE_EQ(f.expensive_seconds, done * cut.multi_fidelity->expensive_seconds);
    // Tuned at the wave's end only: not yet.
    EXPECT_EQ(f.next_continue_if_accepted, WaveFidelity{}.next_continue_if_accepted);
    EXPECT_EQ(f.cost_ratio, WaveFidelity{}.cost_ratio);
    for (const Particle& p : point.partial_accepted) {
      EXPECT_EQ(p.low_distance.size(), 2u);
      if (!p.confirmed) {
        EXPECT_EQ(p.multiplier, 1.0);
      }
    }
    // The completed wave carries the etas it tuned for the wave being resumed.
    ASSERT_EQ(point.completed.size(), 1u);
    ExpectSameFidelity(
        history.waves[0].multi_fidelity, point.completed[0].multi_fidelity, /*ended=*/true);
  };
  check_point(HistoryStore::Open(path, /*read_only=*/true).LoadResumePoint());
  {
    HistoryStore store = HistoryStore::Open(path);
    check_point(store.BeginResume());
    // The resumed wave goes on to its end: the history is the uninterrupted one.
    testing::RecordWave(store, history.waves[1], kBatch);
    store.Finish(history.summary);
  }
  ExpectSameMultiFidelityHistory(history, HistoryStore::Open(path, true).LoadHistory());
  EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
}

TEST_F(HistoryMultiFidelityTest, AnInterruptedWaveReopenedForgetsItsTunedEtas) {
  testing::FakeRunOptions options;
  options.waves = 2;
  options.per_wave = 12;
  options.dimension = 10;
  options.points = 8;
  options.multi_fidelity = true;
  RunHistory history = testing::MakeFakeHistory(options);
  WaveRecord& interrupted = history.waves[1];
  interrupted.complete = false;  // ended, not complete: BeginResume reopens it
  const std::string path = Path("interrupted.db");
  {
    HistoryStore store = HistoryStore::Create(path, testing::MakeFakeMetadata(options));
    for (const WaveRecord& wave : history.waves) testing::RecordWave(store, wave, 5);
  }
  EXPECT_EQ(HistoryStore::Open(path, true).LoadHistory().waves[1].multi_fidelity->cost_ratio, 50.0);
  HistoryStore store = HistoryStore::Open(path);
  const ResumePoint point = store.BeginResume();
  ASSERT_TRUE(point.partial_fidelity.has_value());
  EXPECT_EQ(point.partial_fidelity->expensive_simulations,
            interrupted.multi_fidelity->expensive_simulations);
  EXPECT_EQ(point.partial_fidelity->cost_ratio, 0.0);
  EXPECT_EQ(point.partial_fidelity->next_continue_if_accepted, 1.0);
}

// The new columns are checked on every read and by Verify: one line naming wave and field.
TEST_F(HistoryMultiFidelityTest, InconsistentColumnsAreDataErrorsNamingWaveAndField) {
  testing::FakeRunOptions options;
  options.waves = 2;
  options.per_wave = 12;
  options.dimension = 10;
  options.points = 8;
  options.multi_fidelity = true;
  const RunHistory history = testing::MakeFakeHistory(options);
  struct Case {
    const char* sql;
    const char* mentions;
  };
  const char* first_unconfirmed =
      "(SELECT min(candidate) FROM particle WHERE wave = 1 AND confirmed = 0)";
  const std::string unconfirmed_multiplier =
      std::string("UPDATE particle SET multiplier = 4 WHERE wave = 1 AND candidate = ") +
      first_unconfirmed;
  const std::string no_low_distance =
      std::string("UPDATE particle SET low_distance = NULL WHERE wave = 1 AND candidate = ") +
      first_unconfirmed;
  for (const Case& c : {
           Case{unconfirmed_multiplier.c_str(), "multiplier: corrupt run history: is 4"},
           Case{no_low_distance.c_str(), "low_distance"},
           Case{"UPDATE particle SET confirmed = 2 WHERE wave = 1", "confirmed"},
           Case{"UPDATE wave SET expensive_simulations = candidates + 1 WHERE wave = 1",
                "more than the wave's"},
           Case{"UPDATE wave SET expensive_simulations = 0 WHERE wave = 1",
                "fewer than the wave's"},
           Case{"UPDATE wave SET continue_if_rejected = 0 WHERE wave = 1", "continue_if_rejected"},
           Case{"UPDATE wave SET continue_if_accepted = NULL WHERE wave = 1",
                "other multi-fidelity columns are not"},
           Case{"UPDATE wave SET cheap_seconds = -1 WHERE wave = 1", "cheap_seconds"},
       }) {
    SCOPED_TRACE(c.sql);
    const std::string path = Path("damaged.db");
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix);
    {
      HistoryStore store = HistoryStore::Create(path, testing::MakeFakeMetadata(options));
      for (const WaveRecord& wave : history.waves) testing::RecordWave(store, wave, 5);
      store.Finish(history.summary);
    }
    ASSERT_TRUE(HistoryStore::Verify(path).problems.empty());
    Sql(path, c.sql);
    const HistoryCheck check = HistoryStore::Verify(path);
    ASSERT_FALSE(check.problems.empty());
    bool named = false;
    for (const std::string& problem : check.problems) {
      named = named || (problem.find("wave 2") != std::string::npos &&
                        problem.find(c.mentions) != std::string::npos);
    }
    EXPECT_TRUE(named) << check.problems.front();
  }
}

// A single-fidelity run writes NULL in every multi-fidelity column and reads back without them.
TEST_F(HistoryMultiFidelityTest, ASingleFidelityRunHasNoMultiFidelityColumns) {
  testing::FakeRunOptions options;
  options.waves = 2;
  options.per_wave = 10;
  options.dimension = 8;
  options.points = 6;
  const std::string path = Path("single.db");
  {
    HistoryStore store = HistoryStore::Create(path, testing::MakeFakeMetadata(options));
    for (const WaveRecord& wave : testing::MakeFakeHistory(options).waves) {
      testing::RecordWave(store, wave, 4);
    }
  }
  for (const WaveRecord& wave : HistoryStore::Open(path, true).LoadHistory().waves) {
    EXPECT_FALSE(wave.multi_fidelity.has_value());
    for (const Particle& p : wave.particles) {
      EXPECT_EQ(p.multiplier, 1.0);
      EXPECT_FALSE(p.confirmed);
      EXPECT_TRUE(p.low_distance.empty());
    }
  }
  history::Database db(path, /*create=*/false, /*read_only=*/true);
  EXPECT_EQ(db.QueryInt("SELECT count(*) FROM particle WHERE multiplier IS NOT NULL OR confirmed "
                        "IS NOT NULL OR low_distance IS NOT NULL"),
            0);
  EXPECT_EQ(db.QueryInt("SELECT count(*) FROM wave WHERE continue_if_accepted IS NOT NULL OR "
                        "expensive_simulations IS NOT NULL OR cost_ratio IS NOT NULL"),
            0);
}

}  // namespace
}  // namespace combabc
