// Resume against the run's fingerprint: a run whose inputs, as this combabc rebuilds them from the
// stored configuration, differ from when it started is refused (exit 78, one line naming what
// changed and the file); an unchanged run, or one from before fingerprints, resumes. The runs are
// tiny (3 + 3 clamps, a 2 x 2 mesh per section) so that this stays a unit test.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "cli_runner.hpp"
#include "combabc/history/history_store.hpp"
#include "tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

const std::string kConfig = TinySensorConfig("seed = 3\nwaves = 2\naccepted_per_wave = 5\n",
                                             "[output]\ndirectory = \"out\"\n");

void WriteData(const TempFolder& dir, double peak) { WriteTinySensorData(dir.path(), peak); }

// A run that stops on one of its stopping rules says why on stderr, and keeps its history.
TEST(Stopping, TheReasonIsOnScreen) {
  TempFolder dir("e2e-stopping");
  std::string config = kConfig;
  config.replace(config.find("accepted_per_wave = 5"),
                 std::string("accepted_per_wave = 5").size(),
                 "accepted_per_wave = 500\nmax_simulations = 300");
  std::ofstream(dir / "run.toml") << config;
  WriteData(dir, 1.0);
  const auto r = RunCli({"run", dir / "run.toml", "--no-report"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("stopped: simulation budget of 300 reached in wave 1"), std::string::npos)
      << r.err;
  const RunMetadata m = HistoryStore::Open(dir / "out/history.sqlite", true).LoadMetadata();
  EXPECT_EQ(m.termination, "budget_exhausted");
  EXPECT_EQ(m.summary_message, "simulation budget of 300 reached in wave 1");
  // In wave 1 nothing says the waves grow dear: no advice on the sampler.
  EXPECT_EQ(r.err.find("resample_move"), std::string::npos) << r.err;

  // A rejection run stopped on its acceptance floor after its first wave is pointed to
  // resample-move.
  config = kConfig;
  const std::string waves = "waves = 2\naccepted_per_wave = 5";
  config.replace(config.find(waves),
                 waves.size(),
                 "waves = 3\naccepted_per_wave = 20\nmin_acceptance_rate = 0.9\n"
                 "acceptance_floor_after = 20");
  std::ofstream(dir / "floor.toml") << config;
  const auto floor =
      RunCli({"run", dir / "floor.toml", "--no-report", "-o", dir / "floor"}, dir.path());
  ASSERT_EQ(floor.exit_code, 0) << floor.err;
  EXPECT_NE(floor.err.find("below min_acceptance_rate = 0.9"), std::string::npos) << floor.err;
  EXPECT_NE(floor.err.find("[sampler] method = \"resample_move\""), std::string::npos) << floor.err;
}

class ResumeFingerprint : public ::testing::Test {
 protected:
  ResumeFingerprint() : dir_("e2e-fingerprint") {}
  void SetUp() override {
    std::ofstream(dir_ / "run.toml") << kConfig;
    WriteData(dir_, 1.0);
    const auto r = RunCli({"run", dir_ / "run.toml", "--no-report"}, dir_.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    finished_ = HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadMetadata();
  }

  // A run that was started with `metadata` and killed before its first batch.
  std::string Started(const std::string& name, const RunMetadata& metadata) {
    std::string path = dir_ / name;
    HistoryStore::Create(path, metadata);
    return path;
  }

  RunMetadata With(const std::string& part, const std::string& digest) const {
    RunMetadata m = finished_;
    bool found = false;
    for (auto& [name, value] : m.fingerprint) {
      if (name == part) value = digest, found = true;
    }
    EXPECT_TRUE(found) << "the run stores no fingerprint_" << part;
    return m;
  }

  TempFolder dir_;
  RunMetadata finished_;
};

TEST_F(ResumeFingerprint, ARunStoresEveryPartAndTheCombinedOne) {
  std::vector<std::string> parts;
  for (const auto& [name, digest] : finished_.fingerprint) {
    parts.push_back(name);
    EXPECT_EQ(digest.size(), 16u) << name;
  }
  EXPECT_EQ(parts,
            (std::vector<std::string>{
                "combined", "data", "metric", "sampler", "simulator", "space", "version"}));
}

// The unchanged run resumes and gives the uninterrupted run's history, even with the data CSV
// rewritten meanwhile: resume continues with the data the run stored, never the CSV as it reads
// today, so the CSV cannot change a run under way.
TEST_F(ResumeFingerprint, AnUnchangedRunResumesToTheSameHistoryWhateverTheCsvSaysNow) {
  const std::string path = Started("started.sqlite", finished_);
  WriteData(dir_, 2.0);
  const auto r = RunCli({"resume", path, "--no-report"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string where;
  EXPECT_TRUE(SameHistory(HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadHistory(),
                          HistoryStore::Open(path, true).LoadHistory(),
                          &where))
      << where;
}

TEST_F(ResumeFingerprint, ARunFromBeforeFingerprintsResumesUnchecked) {
  RunMetadata old = With("sampler", "0000000000000000");
  old.fingerprint.clear();
  const auto r = RunCli({"resume", Started("old.sqlite", old), "--no-report"}, dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// Each part as resume would find it changed (the stored digest stands for the run's inputs when
// it started): refused before anything is rewritten, naming the part and what to do.
TEST_F(ResumeFingerprint, AChangedPartIsRefusedNamingIt) {
  struct Case {
    const char* part;
    const char* says;
  };
  for (const Case& c : {
           Case{"data",
                "resume: the measured data changed since the run started (data.csv: "
                "fingerprint_data differs); start a new run or restore the file"},
           Case{"sampler", "the sampler options ([sampler], [sampler.moves], [proposal])"},
           Case{"space", "the parameter space"},
           Case{"metric", "the metric ([metric])"},
           Case{"simulator", "the simulator (its kind, and [model] for the sensor"},
           Case{"version",
                "is not the one that started the run (0.0.9): fingerprint_version "
                "differs; resume with combabc 0.0.9 or start a new run"},
       }) {
    SCOPED_TRACE(c.part);
    RunMetadata changed = With(c.part, "0123456789abcdef");
    if (std::string(c.part) == "version") changed.combabc_version = "0.0.9";
    const std::string path = Started(std::string(c.part) + ".sqlite", changed);
    const auto r = RunCli({"resume", path, "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, 78) << r.err;
    EXPECT_NE(r.err.find(path + ": resume: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string("fingerprint_") + c.part + " differs"), std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
    const RunMetadata after = HistoryStore::Open(path, true).LoadMetadata();
    EXPECT_EQ(after.resume_count, 0) << "refused before BeginResume";
    EXPECT_EQ(after.status, RunStatus::kRunning);
  }
  // Several parts: the first is explained, the others listed.
  RunMetadata two = With("metric", "0123456789abcdef");
  for (auto& [name, value] : two.fingerprint) {
    if (name == "simulator") value = "0123456789abcdef";
  }
  const auto r = RunCli({"resume", Started("two.sqlite", two), "--no-report"}, dir_.path());
  EXPECT_EQ(r.exit_code, 78);
  EXPECT_NE(r.err.find("(also fingerprint_simulator)"), std::string::npos) << r.err;
}

// The sampling method is part of the sampler's fingerprint: a rejection run whose stored
// configuration now asks for resample-move waves (or other move options) is refused, since its
// continuation would not be the run it started as. A rejection run's digest is the one it had
// before the method existed (the resumes above, and OldDefaultTheory's history of an older
// combabc).
TEST_F(ResumeFingerprint, ARunResumedUnderAnotherMethodIsRefused) {
  for (const char* method : {"method = \"resample_move\"\n",
                             "method = \"resample_move\"\n[sampler.moves]\nmax_rounds = 3\n"}) {
    SCOPED_TRACE(method);
    RunMetadata changed = finished_;
    const std::size_t sampler = changed.config_text.find("seed = 3\n");
    ASSERT_NE(sampler, std::string::npos);
    // [sampler.moves] must come after [sampler]'s own keys: at the end of the table's keys.
    const std::size_t end = changed.config_text.find("accepted_per_wave = 5\n", sampler);
    ASSERT_NE(end, std::string::npos);
    changed.config_text.insert(end + std::string("accepted_per_wave = 5\n").size(), method);
    const std::string path = Started("method.sqlite", changed);
    const auto r = RunCli({"resume", path, "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, 78) << r.err;
    EXPECT_NE(r.err.find("fingerprint_sampler differs"), std::string::npos) << r.err;
    fs::remove(path);
  }
}

// A resample-move run through the CLI: each move wave's line says what its moves did, as its
// history records it; a run stopped inside a move wave and resumed (its wave reopened, its move
// columns written anew) gives the uninterrupted run's history, moves and ancestors included.
TEST(ResampleMove, TheTerminalSaysWhatTheMovesDidAndAResumeGivesTheSameHistory) {
  TempFolder dir("e2e-moves");
  WriteData(dir, 1.0);
  const std::string sampler =
      "seed = 3\nwaves = 3\naccepted_per_wave = 10\nmethod = \"resample_move\"\n";
  std::ofstream(dir / "whole.toml") << TinySensorConfig(
      sampler, "[sampler.moves]\nmax_rounds = 4\n[output]\ndirectory = \"whole\"\n");
  std::ofstream(dir / "cut.toml") << TinySensorConfig(
      sampler + "max_simulations = 30\n",
      "[sampler.moves]\nmax_rounds = 4\n[output]\ndirectory = \"cut\"\n");
  const auto whole = RunCli({"run", dir / "whole.toml", "--no-report"}, dir.path());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const RunHistory h = HistoryStore::Open(dir / "whole/history.sqlite", true).LoadHistory();
  ASSERT_EQ(h.waves.size(), 3u);
  EXPECT_FALSE(h.waves[0].moves.has_value());
  for (std::size_t t = 1; t < h.waves.size(); ++t) {
    ASSERT_TRUE(h.waves[t].moves.has_value()) << "wave " << t + 1;
    const WaveMoves& m = *h.waves[t].moves;
    const std::string line = "moves: " + std::to_string(m.rounds) + " rounds, " +
                             std::to_string(m.proposed) + " proposals, ";
    EXPECT_NE(whole.err.find(line), std::string::npos) << line << " in " << whole.err;
    for (const Particle& p : h.waves[t].particles) EXPECT_GE(p.ancestor, 0);
  }

  const auto cut = RunCli({"run", dir / "cut.toml", "--no-report"}, dir.path());
  ASSERT_EQ(cut.exit_code, 0) << cut.err;
  const std::string stopped = dir / "cut/history.sqlite";
  ASSERT_EQ(HistoryStore::Open(stopped, true).LoadMetadata().termination, "budget_exhausted");
  const auto resumed =
      RunCli({"resume", stopped, "--no-report", "--max-simulations", "0"}, dir.path());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  std::string where;
  EXPECT_TRUE(SameHistory(h, HistoryStore::Open(stopped, true).LoadHistory(), &where)) << where;
  EXPECT_TRUE(HistoryStore::Verify(stopped).problems.empty());
}

// Issue 35: the history's experiment table (names, descriptions and how its outputs, data and
// components are sliced per experiment) is not in the fingerprint; one that disagrees with the
// run's configuration (a crafted or damaged history) is refused, naming what differs, before
// anything is rewritten. (With one experiment its counts must add up to the run's, which
// HistoryStore::Create checks, so only its name and description can disagree here.)
TEST_F(ResumeFingerprint, AnExperimentTableThatDisagreesWithTheConfigurationIsRefused) {
  struct Case {
    const char* name;
    std::function<void(StoredExperiment&)> edit;
    const char* says;
  };
  for (const Case& c : {
           Case{"name",
                [](StoredExperiment& x) { x.name = "left"; },
                "experiment 1's name is 'left' in the table and '' as this combabc reads"},
           Case{"description",
                [](StoredExperiment& x) { x.description = "load at 0.2 m"; },
                "experiment 1's description is 'load at 0.2 m' in the table and 'load at 0.45 m"},
       }) {
    SCOPED_TRACE(c.name);
    RunMetadata crafted = finished_;
    ASSERT_EQ(crafted.experiments.size(), 1u);
    c.edit(crafted.experiments[0]);
    const std::string path = Started(std::string(c.name) + ".sqlite", crafted);
    const auto r = RunCli({"resume", path, "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, 78) << r.err;
    EXPECT_NE(r.err.find(path + ": resume: the history's experiment table disagrees with its "
                                "configuration: "),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "one line: " << r.err;
    EXPECT_EQ(HistoryStore::Open(path, true).LoadMetadata().resume_count, 0);
  }
}

}  // namespace
}  // namespace combabc::testing
