// The CLI with the shipped external simulators (examples/custom-simulator) copied into a folder
// whose path has a space and shell metacharacters: a run through the Python worker and through the
// Python command simulator, a resume that continues with the same simulator and gives the
// uninterrupted history, and a resume refused (exit 78, naming what changed) when the simulator
// changed. Also keeps the README's worker the shipped one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>
#include <utility>

#include "cli_runner.hpp"
#include "combabc/history/history_store.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kExample = fs::path(COMBABC_SOURCE_DIR) / "examples/custom-simulator";

class ExternalSimulatorCli : public ::testing::Test {
 protected:
  ExternalSimulatorCli() : dir_("e2e-external simulator $(touch pwned)") {}

  // The example's config `name`, shrunk to a tiny run, written into the scratch folder.
  std::string Config(const std::string& name, int accepted) const {
    for (const char* file : {"worker.py", "model.py", "data.csv"}) {
      fs::copy_file(kExample / file, dir_.path() / file, fs::copy_options::overwrite_existing);
    }
    std::string text = ReadFile(kExample / name);
    text = std::regex_replace(text, std::regex("waves = 5"), "waves = 2");
    text = std::regex_replace(text,
                              std::regex("accepted_per_wave = 40"),
                              "accepted_per_wave = " + std::to_string(accepted));
    text = std::regex_replace(
        text, std::regex("directory = \"results-[a-z]+\""), "directory = \"out\"");
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }

  std::string Started(const std::string& name, const RunMetadata& metadata) const {
    std::string path = dir_ / name;
    HistoryStore::Create(path, metadata);
    return path;
  }

  void RunsResumesAndRefusesAChange(const std::string& config,
                                    const std::string& change_file,
                                    const std::string& from,
                                    const std::string& to,
                                    const std::string& says) {
    const auto r = RunCli({"run", config, "--no-report", "--threads", "2"}, dir_.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string history = dir_ / "out/history.sqlite";
    EXPECT_FALSE(fs::exists(dir_ / "out/history.work")) << "the work folder is removed";
    EXPECT_FALSE(fs::exists(dir_.path() / "pwned"));
    const RunMetadata finished = HistoryStore::Open(history, true).LoadMetadata();
    EXPECT_EQ(finished.output_positions.size(), 21u);
    EXPECT_NE(finished.config_path.find(dir_.path().string()), std::string::npos)
        << "stored absolute: " << finished.config_path;

    // A run killed before its first batch resumes with the same simulator: same history.
    const std::string started = Started("started.sqlite", finished);
    const auto resumed = RunCli({"resume", started, "--no-report"}, dir_.path());
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    std::string where;
    EXPECT_TRUE(SameHistory(HistoryStore::Open(history, true).LoadHistory(),
                            HistoryStore::Open(started, true).LoadHistory(),
                            &where))
        << where;

    // The simulator changed since: refused, saying what changed, before anything is rewritten.
    RunMetadata changed_metadata = finished;
    if (change_file.empty()) {
      const std::size_t at = changed_metadata.config_text.find(from);
      ASSERT_NE(at, std::string::npos);
      changed_metadata.config_text.replace(at, from.size(), to);
    }
    const std::string refused = Started("refused.sqlite", changed_metadata);
    if (!change_file.empty()) {
      std::string text = ReadFile(dir_ / change_file);
      const std::size_t at = text.find(from);
      ASSERT_NE(at, std::string::npos);
      text.replace(at, from.size(), to);
      std::ofstream(dir_ / change_file) << text;
    }
    const auto r2 = RunCli({"resume", refused, "--no-report"}, dir_.path());
    EXPECT_EQ(r2.exit_code, 78) << r2.err;
    EXPECT_NE(r2.err.find(says), std::string::npos) << r2.err;
    EXPECT_EQ(HistoryStore::Open(refused, true).LoadMetadata().resume_count, 0);
  }

  TempFolder dir_;
};

TEST_F(ExternalSimulatorCli, ThePythonWorkerRunsResumesAndAChangedWorkerIsRefused) {
  RunsResumesAndRefusesAChange(Config("worker.toml", 10),
                               "worker.py",
                               "example-supports 1.0",
                               "example-supports 2.0",
                               "the worker's handshake is now 'combabc-worker 2 21 "
                               "example-supports 2.0'");
}

TEST_F(ExternalSimulatorCli, ThePythonCommandRunsResumesAndAChangedCommandIsRefused) {
  RunsResumesAndRefusesAChange(Config("command.toml", 6),
                               "",
                               "{config_dir}/model.py",
                               "{config_dir}/other_model.py",
                               "resume: the simulator (its kind, and [model] for the sensor or the "
                               "program, argv");
  // model.py is worker.py's model as a program per simulation: the same seed gives the worker's
  // history. So the worker's run stands for the command's in ExamplePosteriors, which runs the
  // shipped configs as shipped (the command's 397 python3 processes are about a minute of CPU).
  const RunHistory command = HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadHistory();
  fs::rename(dir_ / "out", dir_ / "out-command");
  const auto r = RunCli({"run", Config("worker.toml", 6), "--no-report"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string where;
  EXPECT_TRUE(SameHistory(
      command, HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadHistory(), &where))
      << where;
}

TEST_F(ExternalSimulatorCli, AWorkerThatFailsItsHandshakeIsAConfigErrorAndLeavesNothing) {
  const std::string config = Config("worker.toml", 10);
  std::ofstream(dir_ / "worker.py") << "print('combabc-worker 2 20 wrong size')\n";
  const auto r = RunCli({"run", config, "--no-report"}, dir_.path());
  EXPECT_EQ(r.exit_code, 78) << r.err;
  EXPECT_NE(r.err.find("it declares '20' outputs; the config declares 21"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "no output folder left";
}

// Regression (issue 20, D12): a command whose program does not exist ran 100 failing
// simulations and stopped on the failure fraction (exit 69); a worker's is refused up front (78).
// Both now say so before anything runs, at the config's argv line.
TEST_F(ExternalSimulatorCli, AProgramThatDoesNotExistIsAConfigErrorAtItsArgvLine) {
  for (const char* name : {"command.toml", "worker.toml"}) {
    SCOPED_TRACE(name);
    const std::string config = Config(name, 6);
    std::string text = ReadFile(config);
    const std::smatch argv = [&] {
      std::smatch m;
      std::regex_search(text, m, std::regex("argv = \\[\"python3\""));
      return m;
    }();
    ASSERT_FALSE(argv.empty());
    const int line =
        1 + static_cast<int>(std::count(text.begin(), text.begin() + argv.position(0), '\n'));
    text.replace(static_cast<std::size_t>(argv.position(0)),
                 static_cast<std::size_t>(argv.length(0)),
                 "argv = [\"no-such-simulator-program\"");
    std::ofstream(config) << text;
    const auto r = RunCli({"run", config, "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, 78) << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(config + ":" + std::to_string(line) + ": simulator.argv: "),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("'no-such-simulator-program'"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing ran, nothing written";
  }
}

// Regression (issue 20, D11): a COMBABC_PYTHON without numpy was found out only after sampling
// (exit 73). The run now refuses to start, naming the variable and the module. (python3 -S has
// no site-packages: no numpy.) Issue 35 (E18): so is a COMBABC_PYTHON that is no python at all
// (/bin/false, which failed the check and passed it), or one that exits 0 without running it.
TEST_F(ExternalSimulatorCli, APythonWithoutNumpyForTheReportIsRefusedBeforeSampling) {
  const std::string config = Config("worker.toml", 10);
  const std::string python = dir_ / "python-without-numpy";
  std::ofstream(python) << "#!/bin/sh\nexec /usr/bin/python3 -S \"$@\"\n";
  fs::permissions(python, fs::perms::owner_all);
  for (const auto& [program, says] :
       {std::pair<std::string, std::string>{python, " has no module numpy"},
        {"/bin/false", " did not run the check for numpy (exit status 1)"},
        {"/bin/true", " did not run the check for numpy (exit status 0, no answer)"}}) {
    SCOPED_TRACE(program);
    ASSERT_EQ(::setenv("COMBABC_PYTHON", program.c_str(), 1), 0);
    const auto r = RunCli({"run", config}, dir_.path());
    ::unsetenv("COMBABC_PYTHON");
    EXPECT_EQ(r.exit_code, 73) << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(std::string("report: COMBABC_PYTHON=").append(program).append(says)),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("--no-report"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << "refused before anything was written";
  }
}

TEST_F(ExternalSimulatorCli, SimulateRunsOneConfigurationThroughTheDeclaredSimulator) {
  const std::string config = Config("worker.toml", 10);
  const auto r =
      RunCli({"simulate", config, "--clamps", "111111", "-o", dir_ / "p.csv"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = ReadFile(dir_ / "p.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "position_m,deflection,normalised");
  EXPECT_EQ(CountLines(csv), 22);
  EXPECT_NE(csv.find("\n0.6,0.05,1\n"), std::string::npos) << csv;  // all fixed: the baseline
  EXPECT_FALSE(fs::exists(dir_ / "p.simulate.work"));
  const auto bad =
      RunCli({"simulate", config, "--clamps", "1111", "-o", dir_ / "q.csv"}, dir_.path());
  EXPECT_EQ(bad.exit_code, 64);
  EXPECT_NE(bad.err.find("the simulator has 6 bits"), std::string::npos) << bad.err;
}

// Candidates whose simulation fails (here the worker answers "error" for every configuration
// starting 11, and crashes for 0111...) are failed simulations of the run, with their reasons,
// not the run's end: the run completes within its max_failure_fraction.
TEST_F(ExternalSimulatorCli, FailedSimulationsAreRecordedAndTheRunGoesOn) {
  std::string config = Config("worker.toml", 10);
  std::string worker = ReadFile(dir_ / "worker.py");
  const std::string at = "    try:\n";
  worker.replace(worker.find(at),
                 at.size(),
                 "    if bits.startswith('0111'):\n        sys.exit(3)\n"
                 "    try:\n        if bits.startswith('11'):\n"
                 "            raise ValueError('no convergence')\n");
  std::ofstream(dir_ / "worker.py") << worker;
  std::string text = ReadFile(config);
  text.replace(text.find("seed = 11"), 9, "seed = 11\nmax_failure_fraction = 0.6");
  std::ofstream(config) << text;
  const auto r = RunCli({"run", config, "--no-report"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RunHistory h = HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadHistory();
  EXPECT_GT(h.summary.failures, 0);
  bool crash = false;
  bool reported = false;
  for (const WaveRecord& w : h.waves) {
    for (const SimulationFailure& f : w.failures) {
      crash |= f.reason == "the worker exited with status 3";
      reported |= f.reason == "the worker reported an error: no convergence";
    }
  }
  EXPECT_TRUE(crash);
  EXPECT_TRUE(reported);
  EXPECT_FALSE(fs::exists(dir_ / "out/history.work"));
}

// A run stopped by the failure ceiling (the worker fails for every configuration starting 11, about
// a quarter of them) continues with `resume --max-failure-fraction` to the history of a run that
// had the raised ceiling from the start; without it, resume refuses (exit 64, one line).
TEST_F(ExternalSimulatorCli, ARunStoppedForFailuresResumesWithARaisedCeiling) {
  const std::string config = Config("worker.toml", 10);
  std::string worker = ReadFile(dir_ / "worker.py");
  const std::string at = "    try:\n";
  worker.replace(worker.find(at),
                 at.size(),
                 "    try:\n        if bits.startswith('11'):\n"
                 "            raise ValueError('no convergence')\n");
  std::ofstream(dir_ / "worker.py") << worker;
  const std::string text = ReadFile(config);
  auto with_ceiling = [&](const std::string& name, const std::string& fraction) {
    std::string changed = text;
    changed.replace(
        changed.find("seed = 11"),
        9,
        "seed = 11\nmax_failure_fraction = " + fraction + "\nfailure_fraction_after = 20");
    std::ofstream(dir_ / name) << changed;
    return dir_ / name;
  };
  const auto whole = RunCli(
      {"run", with_ceiling("whole.toml", "0.6"), "-o", dir_ / "whole", "--no-report"}, dir_.path());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const std::string stopped = dir_ / "stopped/history.sqlite";
  const auto r =
      RunCli({"run", with_ceiling("stopped.toml", "0.1"), "-o", dir_ / "stopped", "--no-report"},
             dir_.path());
  ASSERT_EQ(r.exit_code, 69) << r.err;
  EXPECT_NE(r.err.find("--max-failure-fraction"), std::string::npos) << r.err;
  const auto refused = RunCli({"resume", stopped, "--no-report"}, dir_.path());
  EXPECT_EQ(refused.exit_code, 64) << refused.err;
  EXPECT_NE(refused.err.find("resume: the run stopped (too_many_failures: "), std::string::npos)
      << refused.err;
  const auto resumed =
      RunCli({"resume", stopped, "--no-report", "--max-failure-fraction", "0.6"}, dir_.path());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  std::string where;
  EXPECT_TRUE(SameHistory(HistoryStore::Open(dir_ / "whole/history.sqlite", true).LoadHistory(),
                          HistoryStore::Open(stopped, true).LoadHistory(),
                          &where))
      << where;
  EXPECT_EQ(HistoryStore::Open(stopped, true).LoadMetadata().stop_limits,
            (std::vector<std::pair<std::string, std::string>>{{"max_failure_fraction", "0.6"}}));
}

// A run killed mid-wave (SIGKILL; a worker sees its stdin close and exits, a command's process
// group is its own) resumes to the uninterrupted run's history. The worker sleeps 3 ms per
// request so that the run can be caught mid-wave; a command costs a Python start-up per call.
void ExpectKilledMidWaveResumesToTheUninterruptedHistory(const TempFolder& dir,
                                                         const std::string& config) {
  std::string text = ReadFile(config);
  text.replace(text.find("seed = 11"), 9, "seed = 11\nbatch_size = 4\nthreads = 1");
  std::ofstream(config) << text;

  const auto whole = RunCli({"run", config, "-o", dir / "whole", "--no-report"}, dir.path());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const std::string killed_db = dir / "killed/history.sqlite";
  const pid_t pid = SpawnCli({"run", config, "-o", dir / "killed", "--no-report"}, dir.path());
  ASSERT_GT(pid, 0);
  bool killed = false;
  for (int i = 0; i < 20000 && !killed; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    try {
      const auto point = HistoryStore::Open(killed_db, true).LoadResumePoint();
      if (point.has_partial && point.partial_wave >= 1 && !point.partial_accepted.empty()) {
        killed = ::kill(pid, SIGKILL) == 0;
      }
    } catch (const std::exception&) {
      // Not created yet, or mid-write: try again.
    }
  }
  const auto dead = WaitCli(pid, dir.path());
  ASSERT_TRUE(killed) << "the run finished before it could be killed";
  ASSERT_EQ(dead.exit_code, 128 + SIGKILL);
  const auto resumed = RunCli({"resume", killed_db, "--no-report"}, dir.path());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  std::string where;
  EXPECT_TRUE(SameHistory(HistoryStore::Open(dir / "whole/history.sqlite", true).LoadHistory(),
                          HistoryStore::Open(killed_db, true).LoadHistory(),
                          &where))
      << where;
}

TEST_F(ExternalSimulatorCli, AWorkerRunKilledMidWaveResumesToTheUninterruptedHistory) {
  const std::string config = Config("worker.toml", 30);
  std::string worker = ReadFile(dir_ / "worker.py");
  const std::string loop = "for line in sys.stdin:";
  worker.replace(
      worker.find(loop), loop.size(), "import time\nfor line in sys.stdin:\n    time.sleep(0.003)");
  std::ofstream(dir_ / "worker.py") << worker;
  ExpectKilledMidWaveResumesToTheUninterruptedHistory(dir_, config);
}

TEST_F(ExternalSimulatorCli, ACommandRunKilledMidWaveResumesToTheUninterruptedHistory) {
  ExpectKilledMidWaveResumesToTheUninterruptedHistory(dir_, Config("command.toml", 5));
}

// README.md's "Bring your own simulator" shows examples/custom-simulator/worker.py verbatim, so
// the copy users take is the one these tests run.
TEST(ReadmeWorker, IsTheShippedExample) {
  const std::string readme = ReadFile(fs::path(COMBABC_SOURCE_DIR) / "README.md");
  const std::string worker = ReadFile(kExample / "worker.py");
  ASSERT_FALSE(worker.empty());
  EXPECT_NE(readme.find("```python\n" + worker + "```"), std::string::npos)
      << "README.md must show examples/custom-simulator/worker.py verbatim";
}

}  // namespace
}  // namespace combabc::testing
