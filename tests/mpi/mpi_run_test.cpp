// The executor conformance test (issue 10): the same run through 1 and 2 threads and
// `mpirun -np 1/2/3` gives the same history; a rank killed mid-run ends the run with a non-zero
// exit, mpirun's message naming the rank and rank 0's naming the history to resume, keeps the
// finished waves (verify: OK), and `combabc resume`
// (without MPI, or under mpirun) completes it to the uninterrupted history. Tiny sensor model
// (3 + 3 clamps, a 2 x 2 mesh per section), so that it stays a few seconds.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "combabc/history/history_store.hpp"
#include "e2e/cli_runner.hpp"
#include "e2e/tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

std::string Config(int waves, int accepted) {
  return TinySensorConfig("seed = 3\nwaves = " + std::to_string(waves) +
                          "\naccepted_per_wave = " + std::to_string(accepted) + "\n");
}

// `mpirun --oversubscribe -np N combabc ARGS` (np = 0: combabc without mpirun), output to files in
// `dir`, under `timeout` when timeout_s > 0; returns the pid.
pid_t Spawn(int np, const std::vector<std::string>& args, const fs::path& dir, int timeout_s = 0) {
  std::vector<std::string> all;
  if (timeout_s > 0) all = {"timeout", std::to_string(timeout_s)};
  if (np > 0) {
    for (const char* a : {COMBABC_MPIEXEC, "--oversubscribe", "-np"}) all.emplace_back(a);
    all.push_back(std::to_string(np));
  }
  all.push_back(COMBABC_CLI);
  all.insert(all.end(), args.begin(), args.end());
  return SpawnWithOutputIn(std::move(all), dir);
}

// Ranks whose states diverged would wait for each other forever: `timeout` turns that into a
// failure (mpirun passes its SIGTERM on to the ranks).
CliResult Launch(int np, const std::vector<std::string>& args, const fs::path& dir) {
  return WaitCli(Spawn(np, args, dir, np > 0 ? 120 : 0), dir);
}

RunHistory Load(const std::string& path) { return HistoryStore::Open(path, true).LoadHistory(); }

// Waves the run has ended so far (0 while the file is not there yet), read as SQLite allows a
// reader beside the writer.
int EndedWaves(const std::string& path) {
  if (!fs::exists(path)) return 0;
  sqlite3* db = nullptr;
  int ended = 0;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(db, 1000);
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM wave WHERE ended = 1", -1, &s, nullptr) ==
            SQLITE_OK &&
        sqlite3_step(s) == SQLITE_ROW) {
      ended = sqlite3_column_int(s, 0);
    }
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return ended;
}

// The pid of mpirun's child that is MPI rank `rank` (-1 if none): Open MPI starts the local ranks
// as mpirun's children and tells each its rank in OMPI_COMM_WORLD_RANK.
pid_t RankPid(pid_t mpirun, int rank) {
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    std::getline(stat, line);
    const auto close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state = 0;
    pid_t parent = 0;
    rest >> state >> parent;
    if (parent != mpirun) continue;
    const std::string environment = ReadFile(entry.path() / "environ");
    const std::string want = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
    for (std::size_t at = 0; at < environment.size();) {
      const std::size_t end = environment.find('\0', at);
      if (environment.substr(at, end - at) == want) return std::stoi(name);
      if (end == std::string::npos) break;
      at = end + 1;
    }
  }
  return -1;
}

class MpiRun : public ::testing::Test {
 protected:
  MpiRun() : dir_("e2e-mpi") {
    // CI runs as root; Open MPI refuses that unless told twice.
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    WriteTinySensorData(dir_.path(), 1e-3);
  }
  void WriteConfig(const std::string& name, int waves, int accepted) {
    std::ofstream(dir_ / name) << Config(waves, accepted);
  }
  TempFolder dir_;
};

TEST_F(MpiRun, AnyThreadsAndRanksGiveTheSameHistory) {
  WriteConfig("run.toml", 4, 50);
  const std::string config = dir_ / "run.toml";
  auto run = [&](int np, const std::string& threads, const std::string& out) {
    const CliResult r = Launch(
        np, {"run", config, "-o", dir_ / out, "-j", threads, "-q", "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, 0) << out << ": " << r.err;
    // Rank 0 alone prints: one summary, however many ranks.
    EXPECT_EQ(r.out.find("history:"), r.out.rfind("history:")) << out << ": " << r.out;
    return Load(dir_ / (out + "/history.sqlite"));
  };
  const RunHistory reference = run(0, "1", "threads1");
  ASSERT_EQ(reference.waves.size(), 4u);
  for (const auto& [np, threads, out] :
       std::vector<std::tuple<int, std::string, std::string>>{{0, "2", "threads2"},
                                                              {1, "1", "np1"},
                                                              {2, "1", "np2"},
                                                              {3, "1", "np3"},
                                                              {2, "2", "np2-threads2"}}) {
    std::string where;
    EXPECT_TRUE(SameHistory(reference, run(np, threads, out), &where)) << out << ": " << where;
  }
  // Only rank 0 wrote: the history and nothing else in the output directory.
  std::vector<std::string> files;
  for (const auto& f : fs::directory_iterator(dir_ / "np3")) files.push_back(f.path().filename());
  EXPECT_EQ(files, std::vector<std::string>{"history.sqlite"});
  EXPECT_EQ(Launch(0, {"verify", dir_ / "np3/history.sqlite"}, dir_.path()).exit_code, 0);
}

// A multi-fidelity run (a coarser tiny sensor as the cheap model, a fixed cost ratio so that the
// tuning is deterministic): its continuation draws, confirmations and call times cross the ranks
// with the batch's other results, and the history is the same for any threads and ranks.
TEST_F(MpiRun, AMultiFidelityRunIsTheSameForAnyThreadsAndRanks) {
  std::ofstream(dir_ / "mf.toml") << TinySensorConfig(
      "seed = 3\nwaves = 3\naccepted_per_wave = 30\n",
      "[sampler.multi_fidelity]\ncontinue_if_rejected = 0.3\ncost_ratio = 10\n"
      "[simulator.low_fidelity]\nkind = \"sensor\"\n"
      "[simulator.low_fidelity.model.mesh]\nelements_per_section = 1\n"
      "elements_across_width = 1\n");
  const std::string config = dir_ / "mf.toml";
  auto run = [&](int np, const std::string& threads, const std::string& out) {
    const CliResult r = Launch(
        np, {"run", config, "-o", dir_ / out, "-j", threads, "-q", "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, 0) << out << ": " << r.err;
    return Load(dir_ / (out + "/history.sqlite"));
  };
  const RunHistory reference = run(0, "1", "mf-threads1");
  ASSERT_FALSE(reference.waves.empty());
  std::int64_t expensive = 0;
  for (const WaveRecord& w : reference.waves) {
    ASSERT_TRUE(w.multi_fidelity);
    expensive += w.multi_fidelity->expensive_simulations;
  }
  EXPECT_GT(expensive, 0);
  for (const auto& [np, threads, out] : std::vector<std::tuple<int, std::string, std::string>>{
           {0, "2", "mf-threads2"}, {2, "1", "mf-np2"}, {3, "1", "mf-np3"}}) {
    std::string where;
    EXPECT_TRUE(SameHistory(reference, run(np, threads, out), &where)) << out << ": " << where;
  }
}

// A model choice ([model_choice], docs/config.md): two tiny sensors, clamped or simply supported
// clamps. Each model's run crosses the ranks as a plain run does, so under mpirun its history,
// and the model probabilities from them, are those of the run without MPI; only rank 0 writes
// the tables (both ranks wrote them, and one refused the other's files: exit 73). A model
// stopped on its budget and resumed under mpirun, then the model choice run again (it reads the
// finished models), give the uninterrupted model choice.
TEST_F(MpiRun, AModelChoiceIsTheSameForAnyRanksAndResumes) {
  // Data of tests/e2e/enumerate_test.cpp's model choice, where both models fit some clamps.
  const fs::path mc = dir_ / "mc";
  fs::create_directories(mc);
  WriteTinySensorData(mc);
  const std::string text =
      TinySensorModelChoice("seed = 5\nwaves = 2\naccepted_per_wave = 60\n", "3.0, 2.4");
  std::ofstream(mc / "run.toml") << text;
  std::string budget = text;
  budget.replace(budget.find("seed = 5"), 8, "seed = 5\nmax_simulations = 250");
  std::ofstream(mc / "budget.toml") << budget;
  auto run = [&](int np, const std::string& config, const std::string& out) {
    const CliResult r =
        Launch(np, {"run", mc / config, "-o", mc / out, "-j", "1", "-q", "--no-report"}, mc);
    EXPECT_EQ(r.exit_code, 0) << out << ": " << r.err;
    const std::string line = "Model probabilities";
    EXPECT_NE(r.out.find(line), std::string::npos) << out << ": " << r.out;
    EXPECT_EQ(r.out.find(line), r.out.rfind(line)) << out << ": printed by more than rank 0";
  };
  run(0, "run.toml", "np0");
  run(2, "run.toml", "np2");
  const std::string summary = ReadFile(mc / "np0/model_choice/summary.json");
  // Both models have an estimate: their probabilities are numbers, not upper bounds.
  EXPECT_NE(summary.find("\"reached\": true"), std::string::npos) << summary;
  EXPECT_EQ(summary.find("\"reached\": false"), std::string::npos) << summary;
  EXPECT_EQ(ReadFile(mc / "np2/model_choice/summary.json"), summary);
  EXPECT_EQ(ReadFile(mc / "np2/model_choice/waves.csv"),
            ReadFile(mc / "np0/model_choice/waves.csv"));
  for (const std::string model : {"clamped", "pinned"}) {
    std::string where;
    EXPECT_TRUE(SameHistory(Load(mc / ("np0/models/" + model + "/history.sqlite")),
                            Load(mc / ("np2/models/" + model + "/history.sqlite")),
                            &where))
        << model << ": " << where;
  }

  // The budget stops "clamped" (337 simulations) and not "pinned" (177).
  run(2, "budget.toml", "budget");
  EXPECT_EQ(Load(mc / "budget/models/pinned/history.sqlite").summary.termination,
            Termination::kTargetReached);
  const std::string stopped = mc / "budget/models/clamped/history.sqlite";
  EXPECT_EQ(Load(stopped).summary.termination, Termination::kBudgetExhausted);
  const CliResult r =
      Launch(2, {"resume", stopped, "--max-simulations", "0", "-q", "--no-report"}, mc);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  run(2, "budget.toml", "budget");
  EXPECT_EQ(ReadFile(mc / "budget/model_choice/summary.json"), summary);
}

TEST_F(MpiRun, AFailureOnRankZeroEndsEveryRankWithItsExitCode) {
  WriteConfig("run.toml", 2, 10);
  const std::string config = dir_ / "run.toml";
  ASSERT_EQ(
      Launch(0, {"run", config, "-o", dir_ / "out", "-q", "--no-report"}, dir_.path()).exit_code,
      0);
  // The history exists: rank 0 refuses it (73); the others must not wait for it, nor print.
  const CliResult r =
      Launch(3, {"run", config, "-o", dir_ / "out", "-q", "--no-report"}, dir_.path());
  EXPECT_EQ(r.exit_code, 73) << r.err;
  const std::string line = "cannot create output";
  EXPECT_NE(r.err.find(line), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(line), r.err.rfind(line)) << "printed by more than rank 0: " << r.err;
}

TEST_F(MpiRun, ARankKilledMidRunEndsTheRunAndResumeCompletesIt) {
  WriteConfig("run.toml", 12, 300);
  const std::string config = dir_ / "run.toml";
  ASSERT_EQ(
      Launch(0, {"run", config, "-o", dir_ / "whole", "-j", "1", "-q", "--no-report"}, dir_.path())
          .exit_code,
      0);
  const RunHistory whole = Load(dir_ / "whole/history.sqlite");

  const std::string history = dir_ / "killed/history.sqlite";
  const pid_t mpirun =
      Spawn(2, {"run", config, "-o", dir_ / "killed", "-j", "1", "-q", "--no-report"}, dir_.path());
  ASSERT_GT(mpirun, 0);
  // Once two waves are stored, kill rank 1 as a crashed node would be.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (EndedWaves(history) < 2 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const pid_t rank1 = RankPid(mpirun, 1);
  ASSERT_GT(rank1, 0) << "rank 1 not found (did the run end before the kill?)";
  ASSERT_EQ(::kill(rank1, SIGKILL), 0);
  const CliResult r = WaitCli(mpirun, dir_.path());
  EXPECT_NE(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("rank 1"), std::string::npos) << r.err;  // mpirun names the rank
  // Rank 0 says where the work is, on mpirun's SIGTERM, before mpirun's SIGKILL.
  EXPECT_NE(r.err.find("combabc: SIGTERM from mpirun (a rank died, or the job was stopped): the "
                       "batches committed so far are kept in " +
                       history + "; continue with: combabc resume " + history + "\n"),
            std::string::npos)
      << r.err;
  const CliResult verify = Launch(0, {"verify", history}, dir_.path());
  EXPECT_EQ(verify.exit_code, 0) << verify.err;
  EXPECT_NE(verify.out.find(": OK ("), std::string::npos) << verify.out;

  // The finished waves are kept; the run is not marked finished.
  const RunHistory kept = Load(history);
  EXPECT_GE(kept.waves.size(), 2u);
  EXPECT_LT(kept.waves.size(), whole.waves.size()) << "the run ended before the kill";
  ASSERT_TRUE(kept.waves[0].complete && kept.waves[1].complete);

  // Resumed under mpirun from a copy, and without MPI from the original: the whole run, both.
  fs::create_directories(dir_ / "copy");
  for (const char* suffix : {"", "-wal"}) {
    if (fs::exists(history + suffix)) {
      fs::copy_file(history + suffix, dir_ / (std::string("copy/history.sqlite") + suffix));
    }
  }
  const CliResult mpi_resume =
      Launch(3, {"resume", dir_ / "copy/history.sqlite", "-q", "--no-report"}, dir_.path());
  EXPECT_EQ(mpi_resume.exit_code, 0) << mpi_resume.err;
  const CliResult resume = Launch(0, {"resume", history, "-q", "--no-report"}, dir_.path());
  ASSERT_EQ(resume.exit_code, 0) << resume.err;
  std::string where;
  EXPECT_TRUE(SameHistory(whole, Load(history), &where)) << where;
  EXPECT_TRUE(SameHistory(whole, Load(dir_ / "copy/history.sqlite"), &where)) << where;
}

}  // namespace
}  // namespace combabc::testing
