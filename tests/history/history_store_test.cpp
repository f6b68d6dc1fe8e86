// HistoryStore: round trip through the observer interface, crash and resume semantics, errors.
#include "combabc/history/history_store.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <limits>

#include "combabc/core/error.hpp"
#include "history/fake_run.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;
using testing::FakeRunOptions;
using testing::MakeFakeHistory;
using testing::MakeFakeMetadata;
using testing::RecordWave;
using testing::TempFolder;

constexpr std::int64_t kBatch = 4;  // several batches per wave of the small run

// Small enough for the sanitizer build: 3 waves x 20 particles of 10 bits, 12-point curves.
FakeRunOptions SmallRun() {
  FakeRunOptions options;
  options.waves = 3;
  options.per_wave = 20;
  options.dimension = 10;
  options.points = 12;
  return options;
}

class HistoryStoreTest : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return folder_ / name; }

  // Writes `history` completely, as an uninterrupted run would.
  void WriteRun(const std::string& path, const RunHistory& history) {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    for (const WaveRecord& wave : history.waves) RecordWave(store, wave, kBatch);
    store.Finish(history.summary);
  }

  const TempFolder folder_{"history-test"};
  const fs::path dir_ = folder_.path();
};

void ExpectSame(const RunHistory& expected, const RunHistory& actual) {
  std::string where;
  EXPECT_TRUE(SameHistory(expected, actual, &where)) << where;
  ASSERT_EQ(expected.waves.size(), actual.waves.size());
  for (std::size_t t = 0; t < expected.waves.size(); ++t) {
    EXPECT_EQ(expected.waves[t].wall_seconds, actual.waves[t].wall_seconds);
    EXPECT_EQ(expected.waves[t].acceptance_rate, actual.waves[t].acceptance_rate);
  }
}

TEST_F(HistoryStoreTest, RoundTripThroughObserverIsTheSameHistory) {
  const RunHistory history = MakeFakeHistory(SmallRun());
  const std::string path = Path("RUN.db");
  WriteRun(path, history);
  EXPECT_FALSE(fs::exists(path + "-wal")) << "a finished run is one self-contained file";

  const HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
  const RunHistory loaded = store.LoadHistory();
  ExpectSame(history, loaded);
  EXPECT_EQ(loaded.summary.termination, history.summary.termination);
  EXPECT_EQ(loaded.summary.message, history.summary.message);
  EXPECT_EQ(loaded.summary.waves_completed, history.summary.waves_completed);
  EXPECT_EQ(loaded.summary.simulations, history.summary.simulations);

  const ResumePoint point = store.LoadResumePoint();
  EXPECT_EQ(point.completed.size(), history.waves.size());
  EXPECT_FALSE(point.has_partial);
}

TEST_F(HistoryStoreTest, PairCorrelationsOfALoadedHistoryAreTheRunsExactly) {
  // Importance weights, so that the particles weigh differently.
  RunHistory history = MakeFakeHistory(SmallRun());
  for (WaveRecord& wave : history.waves) ComputeWaveStatistics(wave, Estimator::kImportance);
  const std::string path = Path("RUN.db");
  WriteRun(path, history);

  // Not stored: recomputed from the stored bits and weights.
  const RunHistory loaded = HistoryStore::Open(path, /*read_only=*/true).LoadHistory();
  ASSERT_EQ(loaded.waves.size(), history.waves.size());
  const auto d = static_cast<std::size_t>(SmallRun().dimension);
  int between = 0;  // correlations strictly inside (-1, 1) and not 0: the comparison is not trivial
  for (std::size_t t = 0; t < history.waves.size(); ++t) {
    const std::vector<double>& run = history.waves[t].pair_correlations;
    ASSERT_EQ(run.size(), d * d);
    EXPECT_EQ(loaded.waves[t].pair_correlations, run) << "wave " << t << ": bit for bit";
    for (double r : run) between += r != 0.0 && std::abs(r) < 1.0;
  }
  EXPECT_GT(between, 0);
}

TEST_F(HistoryStoreTest, MetadataRoundTrips) {
  const RunMetadata written = MakeFakeMetadata(SmallRun());
  const std::string path = Path("RUN.db");
  HistoryStore::Create(path, written);
  const RunMetadata read = HistoryStore::Open(path).LoadMetadata();
  EXPECT_EQ(read.config_text, written.config_text);
  EXPECT_EQ(read.config_path, written.config_path);
  EXPECT_FALSE(read.combabc_version.empty());
  EXPECT_EQ(read.git_hash, written.git_hash);
  EXPECT_EQ(read.seed, written.seed);
  EXPECT_EQ(read.threads, written.threads);
  EXPECT_FALSE(read.start_time.empty());
  EXPECT_EQ(read.status, RunStatus::kRunning);
  EXPECT_EQ(read.estimator, written.estimator);
  EXPECT_EQ(read.dimension, written.dimension);
  EXPECT_EQ(read.bit_names, written.bit_names);
  EXPECT_EQ(read.bit_prior_one, std::vector<double>(written.bit_names.size(), 0.5))
      << "no priors given: 0.5 each";
  ASSERT_EQ(read.distance_components.size(), 2u);
  EXPECT_EQ(read.distance_components[1].name, "secondary peak");
  EXPECT_EQ(read.distance_components[1].kind, ComponentKind::kIndicator);
  EXPECT_EQ(read.output_positions, written.output_positions);
  EXPECT_EQ(read.position_unit, "m");
  EXPECT_EQ(read.measured.positions, written.measured.positions);
  EXPECT_EQ(read.measured.values, written.measured.values);
  EXPECT_EQ(read.schema_version, kHistorySchemaVersion);
}

// Schema v3: each particle's reals, each wave's means and sds, the reals' priors, the proposal
// options, the tempering form and the fingerprint come back as written.
TEST_F(HistoryStoreTest, RealsProposalOptionsAndFingerprintRoundTrip) {
  FakeRunOptions options = SmallRun();
  options.reals = 2;
  RunMetadata written = MakeFakeMetadata(options);
  written.reals[1].prior = {PriorKind::kTruncatedNormal, 0.5, 4.0, 1.0, 0.25};
  written.proposal.binary = BinaryKernelKind::kLogistic;
  written.proposal.logistic.max_predecessors = 5;
  written.proposal.logistic.ridge = 0.125;
  written.proposal.continuous = ContinuousKernelKind::kOlcm;
  written.proposal.scale = 1.5;
  written.tempering_form = "mixture";
  written.fingerprint = {{"combined", "00000000000000ff"}, {"data", "0123456789abcdef"}};
  const RunHistory history = MakeFakeHistory(options);
  ASSERT_EQ(history.waves[0].particles[0].theta.reals.size(), 2u);
  ASSERT_EQ(history.waves[0].reals_mean.size(), 2u);
  const std::string path = Path("RUN.db");
  {
    HistoryStore store = HistoryStore::Create(path, written);
    for (const WaveRecord& wave : history.waves) RecordWave(store, wave, 7);
    store.Finish(history.summary);
  }
  const HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
  ExpectSame(history, store.LoadHistory());
  const RunMetadata read = store.LoadMetadata();
  ASSERT_EQ(read.reals.size(), 2u);
  EXPECT_EQ(read.reals[0].name, "stiffness_1");
  EXPECT_EQ(read.reals[0].prior.kind, PriorKind::kUniform);
  EXPECT_EQ(read.reals[0].prior.high, 1e5);
  EXPECT_EQ(read.reals[1].prior.kind, PriorKind::kTruncatedNormal);
  EXPECT_EQ(read.reals[1].prior.low, 0.5);
  EXPECT_EQ(read.reals[1].prior.high, 4.0);
  EXPECT_EQ(read.reals[1].prior.mean, 1.0);
  EXPECT_EQ(read.reals[1].prior.sd, 0.25);
  EXPECT_EQ(read.proposal.binary, BinaryKernelKind::kLogistic);
  EXPECT_EQ(read.proposal.logistic.max_predecessors, 5);
  EXPECT_EQ(read.proposal.logistic.ridge, 0.125);
  EXPECT_EQ(read.proposal.logistic.clip, written.proposal.logistic.clip);
  EXPECT_EQ(read.proposal.continuous, ContinuousKernelKind::kOlcm);
  EXPECT_EQ(read.proposal.scale, 1.5);
  EXPECT_EQ(read.tempering_form, "mixture");
  EXPECT_EQ(read.fingerprint, written.fingerprint);
  EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
}

// Two experiments (schema v6): RunMetadata's outputs, measured points and components are their
// slices concatenated; each experiment's name, description and slice sizes come back as written.
RunMetadata TwoExperiments() {
  RunMetadata m = MakeFakeMetadata(SmallRun());
  const int outputs = static_cast<int>(m.output_positions.size());
  const int measured = static_cast<int>(m.measured.positions.size());
  EXPECT_GE(measured, 2) << "the small run must measure a few points";
  m.experiments = {{"near", "load at 0.45 m, scan 0 .. 0.4 m", 5, 1, 1},
                   {"far", "load at 0.45 m, scan 0.45 .. 0.9 m", outputs - 5, measured - 1, 1}};
  return m;
}

void ExpectSameExperiments(const std::vector<StoredExperiment>& expected,
                           const std::vector<StoredExperiment>& actual) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t e = 0; e < expected.size(); ++e) {
    SCOPED_TRACE("experiment " + std::to_string(e));
    EXPECT_EQ(actual[e].name, expected[e].name);
    EXPECT_EQ(actual[e].description, expected[e].description);
    EXPECT_EQ(actual[e].outputs, expected[e].outputs);
    EXPECT_EQ(actual[e].measured, expected[e].measured);
    EXPECT_EQ(actual[e].components, expected[e].components);
  }
}

TEST_F(HistoryStoreTest, ExperimentsRoundTrip) {
  const RunMetadata written = TwoExperiments();
  const std::string path = Path("RUN.db");
  {
    HistoryStore store = HistoryStore::Create(path, written);
    RecordWave(store, MakeFakeHistory(SmallRun()).waves[0], kBatch);
  }
  const RunMetadata read = HistoryStore::Open(path, /*read_only=*/true).LoadMetadata();
  EXPECT_EQ(read.schema_version, kHistorySchemaVersion);
  ExpectSameExperiments(written.experiments, read.experiments);
  EXPECT_EQ(read.output_positions, written.output_positions) << "still concatenated";
  EXPECT_EQ(read.measured.positions, written.measured.positions);
  const HistoryCheck check = HistoryStore::Verify(path);
  EXPECT_TRUE(check.problems.empty()) << check.problems.front();
}

// A RunMetadata without experiments (a config without [[experiment]], or a caller of the library
// that never heard of them) is stored as one unnamed experiment holding everything.
TEST_F(HistoryStoreTest, NoExperimentsIsOneUnnamedExperimentHoldingEverything) {
  const RunMetadata written = MakeFakeMetadata(SmallRun());
  ASSERT_TRUE(written.experiments.empty());
  const std::string path = Path("RUN.db");
  HistoryStore::Create(path, written);
  const RunMetadata read = HistoryStore::Open(path, /*read_only=*/true).LoadMetadata();
  ExpectSameExperiments({{"",
                          "",
                          static_cast<int>(written.output_positions.size()),
                          static_cast<int>(written.measured.positions.size()),
                          static_cast<int>(written.distance_components.size())}},
                        read.experiments);
}

TEST_F(HistoryStoreTest, CreateRefusesExperimentsThatDoNotCutTheRunIntoSlices) {
  struct Case {
    const char* what;
    void (*change)(std::vector<StoredExperiment>&);
    const char* mentions;
  };
  const Case cases[] = {
      {"one output too many",
       [](std::vector<StoredExperiment>& x) { ++x[1].outputs; },
       "outputs add up to 13, the run has 12"},
      {"one measured point too few",
       [](std::vector<StoredExperiment>& x) { --x[0].measured; },
       "measured points add up to"},
      {"a component missing",
       [](std::vector<StoredExperiment>& x) { x[1].components = 0; },
       "distance components add up to 1, the run has 2"},
      {"a repeated name",
       [](std::vector<StoredExperiment>& x) { x[1].name = x[0].name; },
       "the name repeats"},
      {"a negative count balanced by another",
       [](std::vector<StoredExperiment>& x) {
         x[0].outputs = -1;
         x[1].outputs += 6;
       },
       "negative count"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    RunMetadata m = TwoExperiments();
    c.change(m.experiments);
    const std::string path = Path("RUN.db");
    try {
      HistoryStore::Create(path, m);
      ADD_FAILURE() << "created";
    } catch (const Error& error) {
      EXPECT_EQ(error.kind(), ErrorKind::kSoftware);
      EXPECT_NE(std::string(error.what()).find(c.mentions), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
    }
    EXPECT_FALSE(fs::exists(path)) << "no file is left behind";
  }
}

TEST_F(HistoryStoreTest, AParticleWithTheWrongNumberOfRealsIsRefusedWhenWritten) {
  FakeRunOptions options = SmallRun();
  options.reals = 2;
  HistoryStore store = HistoryStore::Create(Path("RUN.db"), MakeFakeMetadata(options));
  WaveRecord wave = MakeFakeHistory(options).waves[0];
  wave.particles[0].theta.reals.pop_back();
  try {
    RecordWave(store, wave, 1000);
    ADD_FAILURE() << "a particle with 1 real in a 2-real run was stored";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kSoftware);
    EXPECT_NE(std::string(error.what()).find("1 reals, the run has 10 and 2"), std::string::npos)
        << error.what();
  }
}

TEST_F(HistoryStoreTest, BitPriorsRoundTrip) {
  RunMetadata m = MakeFakeMetadata(SmallRun());
  m.bit_prior_one.assign(static_cast<std::size_t>(m.dimension), 0.25);
  m.bit_prior_one[3] = 0.9;
  HistoryStore::Create(Path("RUN.db"), m);
  EXPECT_EQ(HistoryStore::Open(Path("RUN.db")).LoadMetadata().bit_prior_one, m.bit_prior_one);
  m.bit_prior_one.pop_back();
  EXPECT_THROW(HistoryStore::Create(Path("bad.db"), m), Error);
  EXPECT_FALSE(fs::exists(Path("bad.db")));
}

TEST_F(HistoryStoreTest, LargeSeedSurvives) {
  RunMetadata m = MakeFakeMetadata(SmallRun());
  m.seed = std::numeric_limits<std::uint64_t>::max();
  HistoryStore::Create(Path("RUN.db"), m);
  EXPECT_EQ(HistoryStore::Open(Path("RUN.db")).LoadMetadata().seed, m.seed);
}

TEST_F(HistoryStoreTest, NonFiniteValuesRoundTrip) {
  RunHistory history = MakeFakeHistory(SmallRun());
  history.waves[0].thresholds = {std::numeric_limits<double>::infinity()};
  history.waves[0].particles[0].log_weight = -std::numeric_limits<double>::infinity();
  history.waves[0].ess = std::numeric_limits<double>::quiet_NaN();
  const std::string path = Path("RUN.db");
  WriteRun(path, history);
  const RunHistory loaded = HistoryStore::Open(path).LoadHistory();
  EXPECT_TRUE(std::isinf(loaded.waves[0].thresholds[0]));
  EXPECT_EQ(loaded.waves[0].particles[0].log_weight, -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(loaded.waves[0].ess)) << "SQLite stores NaN as NULL; read back as NaN";
}

TEST_F(HistoryStoreTest, StoreDroppedBetweenBatchesKeepsExactlyTheCommittedBatches) {
  const RunHistory history = MakeFakeHistory(SmallRun());
  const std::string path = Path("RUN.db");
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], kBatch);
    RecordWave(store, history.waves[1], kBatch, /*stop_after_batches=*/2);
  }  // dropped without Finish, as a crashed process would leave it
  const HistoryStore store = HistoryStore::Open(path);
  EXPECT_EQ(store.LoadMetadata().status, RunStatus::kRunning);
  const ResumePoint point = store.LoadResumePoint();
  ASSERT_EQ(point.completed.size(), 1u);
  RunHistory first;
  first.waves = {history.waves[0]};
  RunHistory completed;
  completed.waves = point.completed;
  ExpectSame(first, completed);
  ASSERT_TRUE(point.has_partial);
  EXPECT_EQ(point.partial_wave, 1);
  EXPECT_EQ(point.partial_next_index, 2 * kBatch);
  std::vector<std::int64_t> expected;
  for (const Particle& p : history.waves[1].particles) {
    if (p.index < 2 * kBatch) expected.push_back(p.index);
  }
  std::vector<std::int64_t> actual;
  for (const Particle& p : point.partial_accepted) actual.push_back(p.index);
  EXPECT_EQ(actual, expected);
  ASSERT_FALSE(point.partial_accepted.empty());
  EXPECT_EQ(point.partial_accepted[0].theta.bits, history.waves[1].particles[0].theta.bits);
  EXPECT_EQ(point.partial_accepted[0].output, history.waves[1].particles[0].output);

  // The history shows the partial wave last, with statistics derived from its particles.
  const RunHistory loaded = store.LoadHistory();
  ASSERT_EQ(loaded.waves.size(), 2u);
  EXPECT_FALSE(loaded.waves[1].complete);
  EXPECT_EQ(loaded.waves[1].candidates, 2 * kBatch);
  EXPECT_EQ(loaded.waves[1].accepted, static_cast<std::int64_t>(expected.size()));
  EXPECT_EQ(loaded.waves[1].marginals_paper.size(), 10u);
  EXPECT_EQ(loaded.summary.waves_completed, 1);
}

TEST_F(HistoryStoreTest, ProcessKilledBetweenBatchesLosesNothingCommitted) {
  const RunHistory history = MakeFakeHistory(SmallRun());
  const std::string path = Path("RUN.db");
  const pid_t child = ::fork();
  ASSERT_NE(child, -1);
  if (child == 0) {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], kBatch);
    RecordWave(store, history.waves[1], kBatch, /*stop_after_batches=*/3);
    ::raise(SIGKILL);  // no destructor, no checkpoint: the batches live only in the WAL
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  EXPECT_TRUE(fs::exists(path + "-wal"));
  // report / export open it read-only and must see the committed batches too.
  EXPECT_EQ(HistoryStore::Open(path, /*read_only=*/true).LoadResumePoint().partial_next_index,
            3 * kBatch);

  HistoryStore store = HistoryStore::Open(path);
  const ResumePoint point = store.LoadResumePoint();
  ASSERT_EQ(point.completed.size(), 1u);
  ASSERT_TRUE(point.has_partial);
  EXPECT_EQ(point.partial_next_index, 3 * kBatch);
  std::size_t expected = 0;
  for (const Particle& p : history.waves[1].particles) expected += p.index < 3 * kBatch;
  EXPECT_EQ(point.partial_accepted.size(), expected);
}

TEST_F(HistoryStoreTest, OverwritingAKilledRunIgnoresItsWal) {
  const RunHistory history = MakeFakeHistory(SmallRun());
  const std::string path = Path("RUN.db");
  const pid_t child = ::fork();
  ASSERT_NE(child, -1);
  if (child == 0) {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], kBatch);
    ::raise(SIGKILL);
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(fs::exists(path + "-wal"));
  HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()), /*overwrite=*/true);
  EXPECT_TRUE(store.LoadHistory().waves.empty()) << "the old run's WAL was replayed";
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".creating"), std::string::npos)
        << "temporary file left behind";
  }
}

// --overwrite replaces a regular file only (issue D1): a FIFO or a device at the history's path is
// refused and left as it was (a symlink to /dev/null in the test's folder stands for the device).
TEST_F(HistoryStoreTest, OverwriteNeverReplacesADeviceOrFifo) {
  ASSERT_EQ(::mkfifo(Path("RUN.db").c_str(), 0600), 0);
  fs::create_symlink("/dev/null", Path("NULL.db"));
  for (const char* name : {"RUN.db", "NULL.db"}) {
    try {
      HistoryStore::Create(Path(name), MakeFakeMetadata(SmallRun()), /*overwrite=*/true);
      ADD_FAILURE() << name << ": no error";
    } catch (const Error& error) {
      EXPECT_EQ(error.kind(), ErrorKind::kCantCreate) << name;
    }
  }
  EXPECT_TRUE(fs::is_fifo(Path("RUN.db")));
  EXPECT_TRUE(fs::is_symlink(Path("NULL.db")));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 2)
      << "a temporary was left behind";
}

// The resume contract, played by hand: continue from the resume point exactly where the engine
// would, and the stored history equals the uninterrupted run's.
TEST_F(HistoryStoreTest, ResumedRunStoresTheSameHistoryAsAnUninterruptedOne) {
  const RunHistory history = MakeFakeHistory(SmallRun());
  const std::string whole = Path("whole.db");
  WriteRun(whole, history);

  const std::string path = Path("RUN.db");
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], kBatch);
    RecordWave(store, history.waves[1], kBatch, /*stop_after_batches=*/2);
  }
  HistoryStore store = HistoryStore::Open(path);
  const ResumePoint point = store.BeginResume();
  ASSERT_TRUE(point.has_partial);
  EXPECT_EQ(store.LoadMetadata().resume_count, 1);
  // Continue wave 1 from next_index, then the rest.
  const WaveRecord& wave1 = history.waves[1];
  WaveRecord start = wave1;
  start.particles.clear();
  store.OnWaveStart(start);
  std::int64_t accepted = static_cast<std::int64_t>(point.partial_accepted.size());
  for (std::int64_t begin = point.partial_next_index; begin < wave1.candidates; begin += kBatch) {
    const std::int64_t end = std::min(begin + kBatch, wave1.candidates);
    std::vector<Particle> batch;
    for (const Particle& p : wave1.particles) {
      if (p.index >= begin && p.index < end) batch.push_back(p);
    }
    accepted += static_cast<std::int64_t>(batch.size());
    BatchProgress progress;
    progress.wave = 1;
    progress.next_index = end;
    progress.accepted = accepted;
    store.OnBatch(progress, batch);
  }
  store.OnWaveEnd(wave1);
  for (std::size_t t = 2; t < history.waves.size(); ++t) {
    RecordWave(store, history.waves[t], kBatch);
  }
  store.Finish(history.summary);

  ExpectSame(HistoryStore::Open(whole).LoadHistory(), store.LoadHistory());
  EXPECT_EQ(store.LoadMetadata().status, RunStatus::kFinished);
}

TEST_F(HistoryStoreTest, BeginResumeDropsAWaveWithoutBatchesAndReopensAnInterruptedWave) {
  const RunHistory history = MakeFakeHistory(SmallRun());
  const std::string path = Path("RUN.db");
  {
    HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
    RecordWave(store, history.waves[0], kBatch);
    RecordWave(store, history.waves[1], kBatch, /*stop_after_batches=*/0);
  }
  {
    HistoryStore store = HistoryStore::Open(path);
    const ResumePoint point = store.BeginResume();
    EXPECT_EQ(point.completed.size(), 1u);
    EXPECT_FALSE(point.has_partial) << "a wave with no committed batch starts again";
    EXPECT_EQ(store.LoadHistory().waves.size(), 1u);
    // Now an interrupted wave: ended, incomplete.
    WaveRecord interrupted = history.waves[1];
    interrupted.particles.resize(3);
    interrupted.candidates = interrupted.particles.back().index + 1;
    interrupted.complete = false;
    RecordWave(store, interrupted, kBatch);
    RunSummary summary;
    summary.termination = Termination::kInterrupted;
    store.Finish(summary);
    EXPECT_EQ(store.LoadMetadata().status, RunStatus::kInterrupted);
    EXPECT_EQ(store.LoadHistory().summary.termination, Termination::kInterrupted);
  }
  HistoryStore store = HistoryStore::Open(path);
  const ResumePoint point = store.BeginResume();
  ASSERT_TRUE(point.has_partial);
  EXPECT_EQ(point.partial_wave, 1);
  EXPECT_EQ(point.partial_accepted.size(), 3u);
  EXPECT_EQ(store.LoadMetadata().status, RunStatus::kRunning);
  EXPECT_EQ(store.LoadMetadata().resume_count, 2);
  EXPECT_TRUE(store.LoadHistory().waves.back().marginals_importance.size() == 10u);
}

TEST_F(HistoryStoreTest, OnWaveEndDropsParticlesTheWaveDidNotKeep) {
  RunHistory history = MakeFakeHistory(SmallRun());
  const std::string path = Path("RUN.db");
  HistoryStore store = HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
  WaveRecord wave = history.waves[0];
  WaveRecord start = wave;
  start.particles.clear();
  store.OnWaveStart(start);
  BatchProgress progress;
  progress.next_index = wave.candidates;
  progress.accepted = static_cast<std::int64_t>(wave.particles.size());
  store.OnBatch(progress, wave.particles);
  wave.particles.pop_back();  // parallel overshoot: the last acceptance was not needed
  store.OnWaveEnd(wave);
  EXPECT_EQ(store.LoadHistory().waves[0].particles.size(), wave.particles.size());
}

TEST_F(HistoryStoreTest, MarkFailedRecordsTheMessage) {
  HistoryStore store = HistoryStore::Create(Path("RUN.db"), MakeFakeMetadata(SmallRun()));
  store.MarkFailed("simulator crashed at wave 0 candidate 3");
  const RunMetadata m = store.LoadMetadata();
  EXPECT_EQ(m.status, RunStatus::kFailed);
  EXPECT_EQ(m.summary_message, "simulator crashed at wave 0 candidate 3");
  EXPECT_FALSE(m.end_time.empty());
}

// --- errors ------------------------------------------------------------------------------------

template <typename F>
Error Catch(F&& f) {
  try {
    f();
  } catch (const Error& error) {
    return error;
  }
  ADD_FAILURE() << "no combabc::Error thrown";
  return Error(ErrorKind::kSoftware, "none");
}

void ExpectOneLine(const Error& error, const std::string& path) {
  const std::string what = error.what();
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  EXPECT_NE(what.find(path), std::string::npos) << what;
}

TEST_F(HistoryStoreTest, CreateRefusesAnExistingFile) {
  const std::string path = Path("RUN.db");
  { std::ofstream(path) << "precious"; }
  const Error error = Catch([&] { HistoryStore::Create(path, MakeFakeMetadata(SmallRun())); });
  EXPECT_EQ(error.kind(), ErrorKind::kCantCreate);
  ExpectOneLine(error, path);
  std::ifstream in(path);
  std::string content;
  in >> content;
  EXPECT_EQ(content, "precious") << "the existing file is untouched";
  // With the flag, it is replaced.
  HistoryStore::Create(path, MakeFakeMetadata(SmallRun()), /*overwrite=*/true);
  EXPECT_EQ(HistoryStore::Open(path).LoadMetadata().status, RunStatus::kRunning);
}

TEST_F(HistoryStoreTest, CreateInAMissingDirectoryFails) {
  const std::string missing = Path("no/such/dir/RUN.db");
  const Error error = Catch([&] { HistoryStore::Create(missing, MakeFakeMetadata(SmallRun())); });
  EXPECT_EQ(error.kind(), ErrorKind::kCantCreate);
  ExpectOneLine(error, missing);
}

TEST_F(HistoryStoreTest, CreateInAReadOnlyDirectoryFails) {
  if (::geteuid() == 0) GTEST_SKIP() << "root ignores directory permissions";
  const fs::path locked = dir_ / "locked";
  fs::create_directories(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  const std::string path = (locked / "RUN.db").string();
  const Error denied = Catch([&] { HistoryStore::Create(path, MakeFakeMetadata(SmallRun())); });
  EXPECT_EQ(denied.kind(), ErrorKind::kCantCreate);
  ExpectOneLine(denied, path);
  EXPECT_FALSE(fs::exists(path));
  fs::permissions(locked, fs::perms::owner_all);
}

TEST_F(HistoryStoreTest, FailedCreateLeavesNoFile) {
  RunMetadata bad = MakeFakeMetadata(SmallRun());
  bad.measured.values.pop_back();  // positions and values disagree
  const std::string path = Path("RUN.db");
  EXPECT_THROW(HistoryStore::Create(path, bad), Error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + "-wal"));
}

TEST_F(HistoryStoreTest, OpenMissingFileIsNoInput) {
  const std::string path = Path("missing.db");
  const Error error = Catch([&] { HistoryStore::Open(path); });
  EXPECT_EQ(error.kind(), ErrorKind::kNoInput);
  ExpectOneLine(error, path);
}

TEST_F(HistoryStoreTest, OpenGarbageIsDataError) {
  const std::string path = Path("garbage.db");
  {
    std::ofstream out(path, std::ios::binary);
    for (int i = 0; i < 4096; ++i) out.put(static_cast<char>(i * 37));
  }
  const Error error = Catch([&] { HistoryStore::Open(path, /*read_only=*/true); });
  EXPECT_EQ(error.kind(), ErrorKind::kData);
  ExpectOneLine(error, path);
}

TEST_F(HistoryStoreTest, OpenForeignOrNewerDatabaseIsDataError) {
  const std::string foreign = Path("foreign.db");
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(foreign.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "CREATE TABLE t (x); INSERT INTO t VALUES (1);", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  Error error = Catch([&] { HistoryStore::Open(foreign); });
  EXPECT_EQ(error.kind(), ErrorKind::kData);
  ExpectOneLine(error, foreign);

  const std::string newer = Path("newer.db");
  HistoryStore::Create(newer, MakeFakeMetadata(SmallRun()));
  ASSERT_EQ(sqlite3_open(newer.c_str(), &db), SQLITE_OK);
  const std::string newer_version = std::to_string(kHistorySchemaVersion + 1);
  sqlite3_exec(db, ("PRAGMA user_version = " + newer_version).c_str(), nullptr, nullptr, nullptr);
  sqlite3_close(db);
  error = Catch([&] { HistoryStore::Open(newer); });
  EXPECT_EQ(error.kind(), ErrorKind::kData);
  EXPECT_NE(std::string(error.what()).find("newer"), std::string::npos) << error.what();
}

// The stop limits a resume sets are kept (a later resume replaces a key, keeps the others) and
// checksummed: a hand-edited limit is a corrupt history, not a silently different run.
TEST_F(HistoryStoreTest, StopLimitsSetOnResumeAreKeptAndChecksummed) {
  const std::string path = Path("RUN.db");
  HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
  EXPECT_TRUE(HistoryStore::Open(path, true).LoadMetadata().stop_limits.empty());
  HistoryStore::Open(path).BeginResume({{"max_failure_fraction", "0.5"}, {"max_simulations", "9"}});
  HistoryStore::Open(path).BeginResume({{"max_simulations", "20"}});
  using Limits = std::vector<std::pair<std::string, std::string>>;
  EXPECT_EQ(HistoryStore::Open(path, true).LoadMetadata().stop_limits,
            (Limits{{"max_failure_fraction", "0.5"}, {"max_simulations", "20"}}));
  EXPECT_TRUE(HistoryStore::Verify(path).problems.empty());
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db,
               "UPDATE meta SET value = '2000' WHERE key = 'stop_limit_max_simulations'",
               nullptr,
               nullptr,
               nullptr);
  sqlite3_close(db);
  const Error error = Catch([&] { HistoryStore::Open(path, true); });
  EXPECT_EQ(error.kind(), ErrorKind::kData);
  EXPECT_NE(std::string(error.what()).find("run_state_hash"), std::string::npos) << error.what();
}

TEST_F(HistoryStoreTest, ReadOnlyStoreRefusesWrites) {
  const std::string path = Path("RUN.db");
  HistoryStore::Create(path, MakeFakeMetadata(SmallRun()));
  HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
  EXPECT_THROW(store.MarkFailed("x"), Error);
}

TEST(RunStatusTest, NamesRoundTrip) {
  for (RunStatus s :
       {RunStatus::kRunning, RunStatus::kFinished, RunStatus::kFailed, RunStatus::kInterrupted}) {
    EXPECT_EQ(ParseEnum<RunStatus>(ToString(s)), s);
  }
  EXPECT_FALSE(ParseEnum<RunStatus>("done").has_value());
  EXPECT_EQ(ParseEnum<Termination>(ToString(Termination::kBudgetExhausted)),
            Termination::kBudgetExhausted);
}

}  // namespace
}  // namespace combabc
