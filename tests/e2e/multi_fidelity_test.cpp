// A multi-fidelity run through the CLI: the tiny sensor as the expensive model and a coarser mesh
// of it as the cheap one ([simulator.low_fidelity]), a few waves of 20 particles. Bad input is
// refused before anything is simulated (exit 78, file, line and key); a resume whose cheap model
// or multi-fidelity options changed is refused; `simulate --low-fidelity` runs the cheap model.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_runner.hpp"
#include "combabc/history/history_store.hpp"
#include "tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kUsage = 64, kConfig = 78;

const std::string kCheap =
    "[simulator.low_fidelity]\n"
    "kind = \"sensor\"\n"
    "[simulator.low_fidelity.model.mesh]\n"
    "elements_per_section = 1\n"
    "elements_across_width = 1\n";

// sampler: the [sampler] body; the rest after it.
std::string Config(const std::string& sampler, const std::string& cheap = kCheap) {
  return TinySensorConfig(sampler,
                          "[sampler.multi_fidelity]\ncontinue_if_rejected = 0.3\ncost_ratio = 10\n"
                          "[output]\ndirectory = \"out\"\n" +
                              cheap);
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class MultiFidelityRun : public ::testing::Test {
 protected:
  MultiFidelityRun() : dir_("e2e-multi-fidelity") {}
  void SetUp() override {
    WriteTinySensorData(dir_.path());
    std::ofstream(dir_ / "run.toml") << Config("seed = 5\nwaves = 3\naccepted_per_wave = 20\n");
    const auto r = RunCli({"run", dir_ / "run.toml", "--no-report", "-q"}, dir_.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    finished_ = HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadMetadata();
  }

  // The run as if started from `config_text` and killed before its first batch.
  std::string Started(const std::string& name, const std::string& config_text) {
    RunMetadata m = finished_;
    m.config_text = config_text;
    std::string path = dir_ / name;
    HistoryStore::Create(path, m);
    return path;
  }

  TempFolder dir_;
  RunMetadata finished_;
};

TEST_F(MultiFidelityRun, RunsAndFingerprintsTheCheapModel) {
  const RunHistory h = HistoryStore::Open(dir_ / "out/history.sqlite", true).LoadHistory();
  ASSERT_EQ(h.waves.size(), 3u);
  for (const WaveRecord& w : h.waves) EXPECT_EQ(w.particles.size(), 20u);
  bool stored = false;
  for (const auto& [part, digest] : finished_.fingerprint) stored |= part == "low_fidelity";
  EXPECT_TRUE(stored) << "no fingerprint_low_fidelity";
  // Unchanged, it resumes.
  const auto r =
      RunCli({"resume", Started("same.sqlite", finished_.config_text), "--no-report"}, dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(MultiFidelityRun, AResumeWithAnotherCheapModelOrOptionsIsRefused) {
  const std::string text = finished_.config_text;
  std::string finer = text;
  finer.replace(finer.find("elements_per_section = 1"), 24, "elements_per_section = 2");
  std::string eta = text;
  eta.replace(eta.find("continue_if_rejected = 0.3"), 26, "continue_if_rejected = 0.5");
  std::string single = text.substr(0, text.find("[simulator.low_fidelity]"));
  single.replace(single.find("[sampler.multi_fidelity]"), 24, "[unused_table_name]");
  single = single.substr(0, single.find("[unused_table_name]")) + "[output]\ndirectory = \"out\"\n";
  for (const std::string& changed : {finer, eta, single}) {
    const auto r =
        RunCli({"resume", Started("changed.sqlite", changed), "--no-report"}, dir_.path());
    EXPECT_EQ(r.exit_code, kConfig) << r.err;
    EXPECT_NE(r.err.find("the multi-fidelity set-up"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("fingerprint_low_fidelity differs"), std::string::npos) << r.err;
    fs::remove(dir_ / "changed.sqlite");
  }
}

TEST_F(MultiFidelityRun, SimulateRunsTheCheapModelOnAsking) {
  const auto cheap = RunCli({"simulate",
                             dir_ / "run.toml",
                             "--clamps",
                             "101001",
                             "-o",
                             dir_ / "cheap.csv",
                             "--low-fidelity"},
                            dir_.path());
  ASSERT_EQ(cheap.exit_code, 0) << cheap.err;
  const auto expensive =
      RunCli({"simulate", dir_ / "run.toml", "--clamps", "101001", "-o", dir_ / "expensive.csv"},
             dir_.path());
  ASSERT_EQ(expensive.exit_code, 0) << expensive.err;
  const std::string a = ReadFile(dir_ / "cheap.csv");
  const std::string b = ReadFile(dir_ / "expensive.csv");
  // The same positions (the cheap one's outputs stand for the expensive one's), other values.
  EXPECT_EQ(std::count(a.begin(), a.end(), '\n'), std::count(b.begin(), b.end(), '\n'));
  EXPECT_NE(a, b);
  std::ofstream(dir_ / "single.toml") << TinySensorConfig("");
  const auto refused = RunCli({"simulate",
                               dir_ / "single.toml",
                               "--clamps",
                               "101001",
                               "-o",
                               dir_ / "x.csv",
                               "--low-fidelity"},
                              dir_.path());
  EXPECT_EQ(refused.exit_code, kUsage) << refused.err;
  EXPECT_NE(refused.err.find("--low-fidelity: the config has no cheap simulator"),
            std::string::npos)
      << refused.err;
}

// Bad input: exit 78 with file, line and key, before anything is simulated or written.
TEST(MultiFidelityBadInput, IsRefusedAtItsKey) {
  TempFolder dir("e2e-multi-fidelity-bad");
  WriteTinySensorData(dir.path());
  struct Case {
    std::string config;
    std::string says;
  };
  const std::string cheap_command =
      "[simulator.low_fidelity]\nkind = \"command\"\nargv = [\"false\", \"{params}\"]\n"
      "[simulator.low_fidelity.bits]\ncount = 6\n"
      "[simulator.low_fidelity.outputs]\ncoordinates = [0.3, 0.4]\n";
  for (const Case& c : {
           Case{Config("", kCheap + "[simulator.low_fidelity.model.clamps]\nper_edge = 2\n"),
                "simulator.low_fidelity.model.clamps.per_edge: the cheap sensor has 4 clamps"},
           Case{Config("", cheap_command), "simulator.low_fidelity.outputs: has no output at 0 m"},
           Case{Config("") + "[sampler.multi_fidelity.x]\n",
                "sampler.multi_fidelity.x: unknown key"},
           Case{TinySensorConfig("[sampler.multi_fidelity]\nfloor = 0\n", kCheap),
                "sampler.multi_fidelity.floor: must be in (0, 1]"},
           Case{TinySensorConfig("[sampler.multi_fidelity]\ncost_ratio = -1\n", kCheap),
                "sampler.multi_fidelity.cost_ratio: must be finite and > 0"},
           Case{TinySensorConfig("[sampler.multi_fidelity]\ncost_ratio = 2\n"),
                "sampler.multi_fidelity: multi-fidelity options need a cheap simulator"},
       }) {
    std::ofstream(dir / "run.toml") << c.config;
    const auto r = RunCli({"run", dir / "run.toml", "--no-report"}, dir.path());
    EXPECT_EQ(r.exit_code, kConfig) << r.err;
    EXPECT_NE(r.err.find("run.toml:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << c.says;
  }
}

}  // namespace
}  // namespace combabc::testing
