// A run stopped on a limit continues with `combabc resume --max-simulations ...` (or another raised
// stop limit) from where it stopped, to the history an uninterrupted run under the raised limit
// writes; without a raised limit it is refused, and a run that ended on its own still is. Tiny
// sensor runs (3 + 3 clamps, a 2 x 2 mesh per section), so that this stays a unit test. The
// failure ceiling is tested with a failing worker in external_simulator_test.cpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "combabc/history/history_store.hpp"
#include "tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

const std::string kConfig =
    TinySensorConfig("seed = 5\nwaves = 3\naccepted_per_wave = 30\nthreads = 2\nLIMITS",
                     "[output]\ndirectory = \"out\"\n");

class RaisedLimits : public ::testing::Test {
 protected:
  RaisedLimits() : dir_("e2e-raised-limits") { WriteTinySensorData(dir_.path()); }

  // Runs the config with `limits` ([sampler] lines) into `name`/; returns its history.
  std::string Run(const std::string& name, const std::string& limits, int expect_exit = 0) {
    std::string config = kConfig;
    config.replace(config.find("LIMITS"), 6, limits);
    std::ofstream(dir_ / (name + ".toml")) << config;
    last_ = RunCli({"run", dir_ / (name + ".toml"), "-o", dir_ / name, "--no-report"}, dir_.path());
    EXPECT_EQ(last_.exit_code, expect_exit) << last_.err;
    return (dir_.path() / name / "history.sqlite").string();
  }

  RunMetadata Metadata(const std::string& history) const {
    return HistoryStore::Open(history, true).LoadMetadata();
  }

  // The exported particles, marginals and curves of `history` (into `history`'s export/).
  std::string Exported(const std::string& history) const {
    const auto r = RunCli({"export", history}, dir_.path());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const fs::path dir = fs::path(history).parent_path() / "export";
    return ReadFile(dir / "particles.csv") + ReadFile(dir / "marginals.csv") +
           ReadFile(dir / "curves.csv");
  }

  void ExpectSameRun(const std::string& whole, const std::string& resumed) const {
    std::string where;
    EXPECT_TRUE(SameHistory(HistoryStore::Open(whole, true).LoadHistory(),
                            HistoryStore::Open(resumed, true).LoadHistory(),
                            &where))
        << where;
    EXPECT_EQ(Exported(whole), Exported(resumed));
  }

  TempFolder dir_;
  CliResult last_;  // of the last Run
};

// The budget stops the run candidate-exactly; a resume with a larger budget continues from that
// candidate and ends where an uninterrupted run with the larger budget ends, particle for
// particle; the raised limit is recorded (verify: OK) and kept by a later resume.
TEST_F(RaisedLimits, ABudgetStopResumesWithALargerBudgetToTheUninterruptedRun) {
  const std::string whole = Run("whole", "max_simulations = 100000\n");
  const RunMetadata finished = Metadata(whole);
  ASSERT_EQ(finished.termination, "max_waves") << finished.summary_message;
  const auto total = HistoryStore::Open(whole, true).LoadHistory().summary.simulations;
  ASSERT_GT(total, 60) << "the budget below must fall inside a wave after the first";

  const std::string stopped = Run("stopped", "max_simulations = " + std::to_string(total - 7));
  ASSERT_EQ(Metadata(stopped).termination, "budget_exhausted");
  // Its answer (issue 22, item 1) is the last complete wave's, and says so.
  EXPECT_NE(last_.out.find("\nanswer: wave 2 of 3, importance estimator"), std::string::npos)
      << last_.out;
  EXPECT_NE(last_.out.find("the numbers are wave 2's: wave 3 is incomplete (budget_exhausted)"),
            std::string::npos)
      << last_.out;

  // Without a raised limit: refused, one line, nothing rewritten.
  const auto again = RunCli({"resume", stopped, "--no-report"}, dir_.path());
  EXPECT_EQ(again.exit_code, 64) << again.err;
  EXPECT_NE(again.err.find("resume: the run stopped (budget_exhausted: simulation budget of " +
                           std::to_string(total - 7) +
                           " reached in wave 3) and would stop again at once; raise the "
                           "limit with --max-simulations"),
            std::string::npos)
      << again.err;
  EXPECT_EQ(again.err.find('\n'), again.err.size() - 1) << "one line: " << again.err;
  EXPECT_EQ(Metadata(stopped).resume_count, 0);
  // Given again, but not raised: refused too.
  const auto same =
      RunCli({"resume", stopped, "--no-report", "--max-simulations", std::to_string(total - 7)},
             dir_.path());
  EXPECT_EQ(same.exit_code, 64) << same.err;

  const auto resumed =
      RunCli({"resume", stopped, "--no-report", "--max-simulations", "100000"}, dir_.path());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("\nanswer: wave 3 of 3, "), std::string::npos) << resumed.out;
  const RunMetadata after = Metadata(stopped);
  EXPECT_EQ(after.termination, "max_waves");
  EXPECT_EQ(after.resume_count, 1);
  EXPECT_EQ(after.stop_limits,
            (std::vector<std::pair<std::string, std::string>>{{"max_simulations", "100000"}}));
  ExpectSameRun(whole, stopped);
  const auto verify = RunCli({"verify", stopped}, dir_.path());
  EXPECT_EQ(verify.exit_code, 0) << verify.err;
  EXPECT_NE(verify.out.find("stop limits set on resume: max_simulations = 100000"),
            std::string::npos)
      << verify.out;
}

// The acceptance floor: a wave that accepts too rarely ends the run; a lower floor continues it.
TEST_F(RaisedLimits, AnAcceptanceFloorStopResumesWithALowerFloor) {
  const std::string whole = Run("whole", "");
  const std::string stopped =
      Run("stopped", "min_acceptance_rate = 0.9\nacceptance_floor_after = 20\n");
  ASSERT_EQ(Metadata(stopped).termination, "acceptance_rate_too_low");
  const auto refused = RunCli({"resume", stopped, "--no-report"}, dir_.path());
  EXPECT_EQ(refused.exit_code, 64) << refused.err;
  EXPECT_NE(refused.err.find("--min-acceptance-rate"), std::string::npos) << refused.err;
  // The config's default floor (1e-4) is what the whole run had.
  const auto resumed =
      RunCli({"resume", stopped, "--no-report", "--min-acceptance-rate", "1e-4"}, dir_.path());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  // acceptance_floor_after = 20 stays: at 1e-4 it cannot fire in runs this small.
  ExpectSameRun(whole, stopped);
}

// A wall-time stop resumes as it is (each resume has its own clock), or with another limit.
TEST_F(RaisedLimits, AWallTimeStopResumesAndARunThatEndedOnItsOwnIsRefused) {
  const std::string whole = Run("whole", "");
  const auto refused =
      RunCli({"resume", whole, "--no-report", "--max-simulations", "9"}, dir_.path());
  EXPECT_EQ(refused.exit_code, 64) << refused.err;
  EXPECT_NE(refused.err.find("the run has already finished (max_waves)"), std::string::npos)
      << refused.err;
  // With the next step.
  EXPECT_NE(refused.err.find("give it more waves: --waves N"), std::string::npos) << refused.err;
  // A bad limit is a usage error before anything is read.
  const auto bad = RunCli({"resume", whole, "--max-failure-fraction", "2"}, dir_.path());
  EXPECT_EQ(bad.exit_code, 64) << bad.err;

  // Small batches, so that the clock (checked between batches) stops a wave before its end.
  const std::string stopped = Run("stopped", "max_wall_time = 1e-9\nbatch_size = 8\n");
  ASSERT_EQ(Metadata(stopped).termination, "wall_time_exceeded");
  const auto resumed = RunCli({"resume", stopped, "--no-report"}, dir_.path());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  // Its own clock stopped it again after one batch: still wall_time_exceeded, a batch further.
  EXPECT_EQ(Metadata(stopped).termination, "wall_time_exceeded");
  const auto unlimited =
      RunCli({"resume", stopped, "--no-report", "--max-wall-time", "0"}, dir_.path());
  ASSERT_EQ(unlimited.exit_code, 0) << unlimited.err;
  ExpectSameRun(whole, stopped);
}

// Issue 36: a run that did all its waves continues with more (--waves, recorded like a raised
// limit) to the history of one longer run; as many waves as it did would stop it at once.
TEST_F(RaisedLimits, AFinishedRunGivenMoreWavesIsOneLongerRun) {
  const std::string whole = Run("whole", "");
  std::string shorter = kConfig;
  shorter.replace(shorter.find("waves = 3"), 9, "waves = 2");
  shorter.replace(shorter.find("LIMITS"), 6, "");
  std::ofstream(dir_ / "two.toml") << shorter;
  const auto run =
      RunCli({"run", dir_ / "two.toml", "-o", dir_ / "two", "--no-report"}, dir_.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string two = (dir_.path() / "two" / "history.sqlite").string();
  ASSERT_EQ(Metadata(two).termination, "max_waves");
  const auto same = RunCli({"resume", two, "--no-report", "--waves", "2"}, dir_.path());
  EXPECT_EQ(same.exit_code, 64) << same.err;
  EXPECT_NE(same.err.find("has done its 2 waves and would stop again at once; give it more with "
                          "--waves above 2"),
            std::string::npos)
      << same.err;
  const auto more = RunCli({"resume", two, "--no-report", "--waves", "3"}, dir_.path());
  ASSERT_EQ(more.exit_code, 0) << more.err;
  EXPECT_EQ(Metadata(two).stop_limits,
            (std::vector<std::pair<std::string, std::string>>{{"waves", "3"}}));
  ExpectSameRun(whole, two);
}

// tests/e2e/data/kirchhoff_default_history.sqlite: a budget-stopped run written by combabc
// before RZT became the sensor's default (examples/sensor-45cm/least_squares.toml at that
// version, reduced to 6 + 6 clamps and a 2 x 2 mesh, max_simulations = 40), whose config has no
// [model] theory because it meant Kirchhoff. Reading that config today gives RZT, whose
// fingerprint differs; the resume must recognise the old default and continue the run it was.
TEST(OldDefaultTheory, AHistoryFromBeforeRztWasTheDefaultResumesAsKirchhoff) {
  TempFolder dir("e2e-old-default-theory");
  const fs::path history = dir.path() / "history.sqlite";
  fs::copy_file(fs::path(COMBABC_SOURCE_DIR) / "tests/e2e/data/kirchhoff_default_history.sqlite",
                history);
  const RunMetadata before = HistoryStore::Open(history, true).LoadMetadata();
  ASSERT_EQ(before.termination, "budget_exhausted");
  ASSERT_EQ(before.config_text.find("theory"), std::string::npos);
  const auto r =
      RunCli({"resume", history, "--no-report", "--max-simulations", "100000"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RunMetadata after = HistoryStore::Open(history, true).LoadMetadata();
  EXPECT_EQ(after.termination, "max_waves");
}

}  // namespace
}  // namespace combabc::testing
