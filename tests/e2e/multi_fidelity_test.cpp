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
  // Three waves, or two when the target is reached first; a multi-fidelity wave ends at 20
  // effective acceptances, so it may hold more particles (docs/algorithm.md).
  ASSERT_GE(h.waves.size(), 2u) << h.summary.message;
  for (const WaveRecord& w : h.waves) {
    EXPECT_TRUE(w.complete) << h.summary.message << " " << w.candidates;
    EXPECT_GE(w.particles.size(), 20u);
  }
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

// An external program (the cheap one beside the sensor or beside another program, or one per
// experiment) works in "<history stem>.work/", which combabc makes whatever the expensive simulator
// is and removes once every simulator working in it has gone: none is left behind, empty or not.
// `sh` programs (a few ms a call) and tiny waves keep this a unit test.
TEST(ExternalWorkFolder, IsMadeForEveryExternalProgramAndRemovedAfterTheRun) {
  TempFolder dir("e2e-work-folder");
  WriteTinySensorData(dir.path());
  // The data's tent at four positions, from a command (CSV on stdout) or a worker (protocol 2).
  const std::string outputs = "coordinates = [0.31, 0.4, 0.49, 0.58]\n";
  const std::string command =
      "kind = \"command\"\n"
      "argv = [\"sh\", \"-c\", 'printf \"0.86\\n0.95\\n0.96\\n0.87\\n\"', \"sh\", \"{params}\"]\n";
  const std::string worker =
      "kind = \"worker\"\n"
      "argv = [\"sh\", \"-c\", 'echo combabc-worker 2 4 tiny; while read id rest; do "
      "echo \"$id ok 0.86 0.95 0.96 0.87\"; done']\n";
  const std::string rest =
      "[sampler]\nseed = 2\nwaves = 1\naccepted_per_wave = 3\n"
      "max_simulations = 60\n[output]\ndirectory = \"out\"\n";
  const std::string cheap = "[simulator.low_fidelity]\n" + command +
                            "[simulator.low_fidelity.bits]\ncount = 6\n"
                            "[simulator.low_fidelity.outputs]\n" +
                            outputs + "[sampler.multi_fidelity]\ncost_ratio = 10\n";
  auto simulator = [&](const std::string& kind) {
    return "[simulator]\n" + kind + "[simulator.bits]\ncount = 6\n[simulator.outputs]\n" + outputs;
  };
  auto experiment = [](const std::string& name) {
    return "[[experiment]]\nname = \"" + name +
           "\"\n[experiment.data]\ncsv = \"data.csv\"\nposition_column = \"position_m\"\n"
           "displacement_column = \"displacement_m\"\nposition_unit = \"m\"\n"
           "displacement_unit = \"m\"\n[experiment.metric]\n[[experiment.metric.component]]\n"
           "type = \"least_squares\"\nwindow = [0.31, 0.58]\n";
  };
  // The tiny sensor's [data] and [metric] for a program as the run's [simulator].
  const std::string sensor = TinySensorConfig("");
  const std::string data_and_metric =
      sensor.substr(sensor.find("[data]"), sensor.find("[sampler]") - sensor.find("[data]"));
  struct Case {
    const char* name;
    std::string config;
  };
  for (const Case& c : {
           Case{"the sensor beside a cheap command",
                TinySensorConfig(
                    "seed = 2\nwaves = 1\naccepted_per_wave = 3\n",
                    std::string("[output]\ndirectory = \"out\"\n")
                        .append(cheap)
                        .append("[model.output]\npositions = [0.31, 0.4, 0.49, 0.58]\n"))},
           Case{"a command beside a cheap command",
                simulator(command).append(data_and_metric).append(rest).append(cheap)},
           Case{"a worker per experiment",
                simulator(worker) + experiment("a") + experiment("b") + rest},
       }) {
    SCOPED_TRACE(c.name);
    std::ofstream(dir / "run.toml") << c.config;
    fs::remove_all(dir / "out");
    const auto r = RunCli({"run", dir / "run.toml", "--no-report", "-q"}, dir.path());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "out/history.sqlite"));
    EXPECT_FALSE(fs::exists(dir / "out/history.work")) << "left behind";
    if (c.config.find("low_fidelity") == std::string::npos) continue;
    const auto simulated = RunCli(
        {"simulate", dir / "run.toml", "--clamps", "101001", "-o", dir / "x.csv", "--low-fidelity"},
        dir.path());
    EXPECT_EQ(simulated.exit_code, 0) << simulated.err;
    EXPECT_FALSE(fs::exists(dir / "x.simulate.work")) << "left behind";
    fs::remove(dir / "x.csv");
  }
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
