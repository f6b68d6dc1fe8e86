// Several [[experiment]] tables end to end on the tiny sensor (3 + 3 clamps, a 2 x 2 mesh per
// section): the joint simulator and distance are each experiment's own, one after the other,
// exactly; the config's refusals through the CLI (exit 78, one "file:line: key: ..." line); and a
// run of three experiments (two plate models) killed mid-wave or before its first batch, or
// stopped by its budget, resumes to the uninterrupted run's history.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "combabc/config/config.hpp"
#include "combabc/config/distance_from_config.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/services/run.hpp"
#include "combabc/services/simulate.hpp"
#include "tiny_experiments.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kConfigError = 78;

// Loads at either end: each experiment sees the clamps of its own end (and their opposites).
const TinyExperiment kRight = Experiment("right", 0.75, 5.0, 0.63, 0.87);
const TinyExperiment kLeft = Experiment("left", 0.15, 5.0, 0.03, 0.27);
// Another frequency (its own plate model), and a scan line of its own (2 cm, off the centre) with
// fewer data points.
const TinyExperiment kLeft7Hz = Experiment("left.7Hz", 0.15, 7.0, 0.03, 0.27);
const TinyExperiment kMid =
    Experiment("mid_2cm", 0.45, 5.0, 0.33, 0.54, "spacing = 0.02\ny_fraction = 0.25\n");

// Configuration i of `dimension` bits: bit k is bit k of i.
std::vector<std::uint8_t> Bits(int i, int dimension) {
  std::vector<std::uint8_t> bits(static_cast<std::size_t>(dimension));
  for (int k = 0; k < dimension; ++k) bits[static_cast<std::size_t>(k)] = (i >> k) & 1;
  return bits;
}

// A config's simulator at its nominal values and its distance over its data, as a run builds
// them.
struct Built {
  std::unique_ptr<JointDistance> distance;
  std::unique_ptr<services::NominalSimulator> simulator;
};

Built Build(const std::string& path) {
  CalibrationConfig config = LoadConfig(path);
  Built built;
  built.distance = MakeDistance(config, ProfilesOf(LoadExperimentData(config)));
  built.simulator = std::make_unique<services::NominalSimulator>(
      std::move(config), (fs::path(path).parent_path() / "work").string());
  return built;
}

struct Setup {
  const char* name;
  std::vector<TinyExperiment> experiments;
};

void PrintTo(const Setup& setup, std::ostream* os) { *os << setup.name; }

class JointEqualsSingles : public ::testing::TestWithParam<Setup> {};

// For every configuration of the 6 clamps: the joint simulator's output is the single-experiment
// simulators' outputs concatenated, bit for bit, and the joint distance is their distances
// concatenated, bit for bit, with the components named "<experiment>/<component>".
TEST_P(JointEqualsSingles, TheJointSimulatorAndDistanceAreTheSingleOnesOneAfterTheOther) {
  const std::vector<TinyExperiment>& experiments = GetParam().experiments;
  ScratchDir dir(std::string("e2e-experiments-joint-") + GetParam().name);
  for (const TinyExperiment& x : experiments) WriteTentData(dir.path(), x);
  const std::string sampler = "seed = 1\n";
  std::ofstream(dir / "joint.toml") << ExperimentsConfig(experiments, sampler);
  const Built joint = Build(dir / "joint.toml");
  std::vector<Built> singles;
  for (const TinyExperiment& x : experiments) {
    std::ofstream(dir / (x.name + ".toml")) << SingleExperimentConfig(x, sampler);
    singles.push_back(Build(dir / (x.name + ".toml")));
  }

  std::vector<double> positions;
  std::vector<DistanceComponent> components;
  std::size_t schedules = 0;
  for (std::size_t e = 0; e < experiments.size(); ++e) {
    const std::vector<double>& one = singles[e].simulator->positions();
    positions.insert(positions.end(), one.begin(), one.end());
    for (DistanceComponent c : singles[e].distance->components()) {
      c.name = experiments[e].name + "/" + c.name;
      components.push_back(c);
    }
    schedules += singles[e].simulator->config().smc.thresholds.size();
  }
  EXPECT_EQ(joint.simulator->positions(), positions);
  ASSERT_EQ(joint.simulator->output_size(), static_cast<int>(positions.size()));
  const std::vector<DistanceComponent> joint_components = joint.distance->components();
  ASSERT_EQ(joint_components.size(), components.size());
  for (std::size_t k = 0; k < components.size(); ++k) {
    EXPECT_EQ(joint_components[k].name, components[k].name);
    EXPECT_EQ(joint_components[k].kind, components[k].kind) << components[k].name;
  }
  EXPECT_EQ(joint.simulator->config().smc.thresholds.size(), schedules);
  EXPECT_EQ(joint.distance->threshold_schedules().size(), schedules);

  const int dimension = joint.simulator->dimension();
  ASSERT_EQ(dimension, 6);
  for (int i = 0; i < (1 << dimension); ++i) {
    const std::vector<std::uint8_t> bits = Bits(i, dimension);
    std::vector<double> outputs, distances;
    for (const Built& single : singles) {
      const std::vector<double> out = single.simulator->Simulate(bits);
      ASSERT_EQ(out.size(), single.distance->output_size());
      outputs.insert(outputs.end(), out.begin(), out.end());
      // The single experiment's own CompositeDistance (its JointDistance's only part).
      ASSERT_EQ(single.distance->parts().size(), 1u);
      const CompositeDistance& d = *single.distance->parts()[0].distance;
      std::vector<double> values(d.components().size());
      d.Evaluate(out, values);
      distances.insert(distances.end(), values.begin(), values.end());
    }
    const std::vector<double> out = joint.simulator->Simulate(bits);
    // The joint model solves every load case with one factorization; a case's outputs equal its
    // own model's to round-off (bit for bit unless another case's load makes a section piece of
    // its own; docs/model.md, "Several load cases").
    ASSERT_EQ(out.size(), outputs.size());
    const double peak = *std::max_element(outputs.begin(), outputs.end());
    for (std::size_t k = 0; k < out.size(); ++k) {
      ASSERT_NEAR(out[k], outputs[k], 1e-12 * peak) << "configuration " << i << ", output " << k;
    }
    std::vector<double> values(components.size());
    joint.distance->Evaluate(out, values);
    for (std::size_t k = 0; k < values.size(); ++k) {
      ASSERT_NEAR(values[k], distances[k], 1e-9 * std::max(1.0, std::abs(distances[k])))
          << "configuration " << i << ", component " << k;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Experiments,
                         JointEqualsSingles,
                         ::testing::Values(
                             // One plate model, its two load cases.
                             Setup{"one_model", {kRight, kLeft}},
                             // Two models (5 and 7 Hz), the 5 Hz one holding experiments 0 and 2
                             // (its outputs scattered around the 7 Hz one's).
                             Setup{"two_models", {kRight, kLeft7Hz, kMid}}),
                         [](const ::testing::TestParamInfo<Setup>& p) {
                           return std::string(p.param.name);
                         });

// `combabc simulate` on the joint config: each experiment's rows (named in the first column,
// normalised by its own peak) are the single-experiment config's rows.
TEST(Experiments, SimulateWritesEachExperimentAsItsOwnConfigDoes) {
  ScratchDir dir("e2e-experiments-simulate");
  const std::vector<TinyExperiment> experiments = {kRight, kLeft};
  std::ofstream(dir / "joint.toml") << ExperimentsConfig(experiments, "seed = 1\n");
  auto r = RunCli({"simulate", dir / "joint.toml", "--clamps", "101101", "-o", dir / "joint.csv"},
                  dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string joint = ReadFile(dir.path() / "joint.csv");
  ASSERT_EQ(joint.substr(0, joint.find('\n')), "experiment,position_m,displacement_m,normalised");
  std::string expected = joint.substr(0, joint.find('\n') + 1);
  for (const TinyExperiment& x : experiments) {
    std::ofstream(dir / (x.name + ".toml")) << SingleExperimentConfig(x, "seed = 1\n");
    r = RunCli({"simulate",
                dir / (x.name + ".toml"),
                "--clamps",
                "101101",
                "-o",
                dir / (x.name + ".out.csv")},
               dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string single = ReadFile(dir.path() / (x.name + ".out.csv"));
    ASSERT_EQ(single.substr(0, single.find('\n')), "position_m,displacement_m,normalised");
    std::size_t at = single.find('\n') + 1;
    for (std::size_t end; (end = single.find('\n', at)) != std::string::npos; at = end + 1) {
      expected += x.name + "," + single.substr(at, end + 1 - at);
    }
  }
  EXPECT_EQ(joint, expected);
}

// The line (1-based) of the `occurrence`-th (0-based) line of `text` starting with `start`.
int LineOf(const std::string& text, const std::string& start, int occurrence = 0) {
  int line = 1;
  std::size_t at = 0;
  while (at < text.size()) {
    if (text.compare(at, start.size(), start) == 0 && occurrence-- == 0) return line;
    const std::size_t end = text.find('\n', at);
    if (end == std::string::npos) break;
    at = end + 1;
    ++line;
  }
  ADD_FAILURE() << "no line " << occurrence << " starting with " << start;
  return 0;
}

void ReplaceOnce(std::string& text, const std::string& what, const std::string& with) {
  const std::size_t at = text.find(what);
  ASSERT_NE(at, std::string::npos) << what;
  text.replace(at, what.size(), with);
}

// Each refusal through `combabc run`: exit 78, one line "FILE:LINE: KEY: ...", before anything is
// written (no output folder).
TEST(Experiments, ConfigRefusalsNameTheFileLineAndKey) {
  ScratchDir dir("e2e-experiments-refusals");
  WriteTentData(dir.path(), kRight);
  WriteTentData(dir.path(), kLeft);
  const std::string base = ExperimentsConfig({kRight, kLeft},
                                             "seed = 1\nwaves = 2\naccepted_per_wave = 5\n",
                                             "[output]\ndirectory = \"out\"\n");
  // The base config runs: every refusal below is the one change's.
  {
    std::ofstream(dir / "base.toml") << base;
    const auto r = RunCli({"run", dir / "base.toml", "--no-report", "-q"}, dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    fs::remove_all(dir.path() / "out");
  }
  struct Case {
    std::string name;
    std::string text;
    int line;
    std::string key;
    std::string says;
  };
  std::vector<Case> cases;
  auto add = [&](std::string name, const std::string& what, const std::string& with) {
    Case c{std::move(name), base, 0, "", ""};
    ReplaceOnce(c.text, what, with);
    cases.push_back(std::move(c));
    return &cases.back();
  };
  {
    Case* c = add("duplicate", "name = \"left\"", "name = \"right\"");
    c->line = LineOf(c->text, "name = \"right\"", 1);
    c->key = "experiment[1].name";
    c->says = "experiment 'right' is already defined at line " +
              std::to_string(LineOf(c->text, "name = \"right\"", 0));
  }
  {
    // Distinct names that export would turn into the same columns.
    Case* c = add("same_columns", "name = \"left\"", "name = \"Right\"");
    c->line = LineOf(c->text, "name = \"Right\"");
    c->key = "experiment[1].name";
    c->says = "experiment 'Right' is already defined at line " +
              std::to_string(LineOf(c->text, "name = \"right\"")) +
              " (names that differ only in case or punctuation would share export columns)";
  }
  {
    // Inside the simulator's outputs (the whole plate), past the left data's 27 cm.
    Case* c = add("window", "window = [0.03, 0.27]", "window = [0.03, 0.3]");
    c->line = LineOf(c->text, "[[experiment.metric.component]]", 1);
    c->key = "experiment[1].metric.component[0]";
    c->says = "window 3-30 cm reaches beyond the measured data, 3-27 cm";
  }
  {
    Case* c = add("top_data", "[sampler]", "[data]\ncsv = \"right.csv\"\n\n[sampler]");
    c->line = LineOf(c->text, "[data]");
    c->key = "data";
    c->says =
        "[data] is the shorthand for one experiment; with [[experiment]] tables give each "
        "its own [experiment.data]";
  }
  {
    Case* c = add("top_metric", "[sampler]", "[metric]\nquantile = 0.3\n\n[sampler]");
    c->line = LineOf(c->text, "[metric]");
    c->key = "metric";
    c->says = "[metric] is the shorthand for one experiment";
  }
  {
    Case* c = add("no_name", "name = \"left\"\n", "");
    c->line = LineOf(c->text, "[[experiment]]", 1);
    c->key = "experiment[1].name";
    c->says = "missing required key";
  }
  for (const std::string& bad :
       std::vector<std::string>{"le/ft", "le ft", "", "..", std::string(65, 'x')}) {
    Case* c = add("bad_name", "name = \"left\"", "name = \"" + bad + "\"");
    c->line = LineOf(c->text, "name = \"" + bad + "\"");
    c->key = "experiment[1].name";
    // The name as an excerpt: quoted, cut after 40 bytes.
    c->says = "'" + (bad.size() > 40 ? bad.substr(0, 40) + "..." : bad) +
              "' must be 1 to 64 letters, digits, '_', '-' or '.'";
  }
  {
    Case* c = add("not_a_string", "name = \"left\"", "name = 3");
    c->line = LineOf(c->text, "name = 3");
    c->key = "experiment[1].name";
    c->says = "expected a string";
  }
  {
    Case* c = add("normalise", "csv = \"left.csv\"", "csv = \"left.csv\"\nnormalise = false");
    c->line = LineOf(c->text, "[[experiment]]", 1);
    c->key = "experiment[1].data.normalise";
    c->says = "must be the same in every experiment";
  }
  {
    Case* c = add("no_data",
                  "[experiment.data]\ncsv = \"left.csv\"",
                  "[experiment.datum]\ncsv = \"left.csv\"");
    c->line = LineOf(c->text, "[[experiment]]", 1);
    c->key = "experiment[1].data";
    c->says = "missing required table [experiment[1].data]";
  }
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    SCOPED_TRACE(c.name);
    const std::string path = dir / (c.name + std::to_string(i) + ".toml");
    std::ofstream(path) << c.text;
    const auto r = RunCli({"run", path, "--no-report"}, dir.path());
    EXPECT_EQ(r.exit_code, kConfigError) << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    const std::string where = path + ":" + std::to_string(c.line) + ": " + c.key + ": ";
    EXPECT_NE(r.err.find(where + c.says), std::string::npos)
        << "want " << where << c.says << "\ngot  " << r.err;
    EXPECT_FALSE(fs::exists(dir.path() / "out")) << r.err;
  }
  // 64 characters, every kind allowed, is a name.
  std::string text = base;
  const std::string longest = std::string(59, 'a') + "Z9_.-";
  ReplaceOnce(text, "name = \"left\"", "name = \"" + longest + "\"");
  ASSERT_EQ(longest.size(), 64u);
  const CalibrationConfig parsed = ParseConfig(text, dir / "longest.toml");
  ASSERT_EQ(parsed.experiments.size(), 2u);
  EXPECT_EQ(parsed.experiments[1].name, longest);
}

// The history of a run as it stands after a SIGKILL that came once `batches` batches of wave
// `wave` (0-based) had been committed, or before the first batch (batches = 0, wave = 0): records
// the run's callbacks into a history of its own, created with the run's metadata at its first
// wave, and stops recording there. The store commits each callback in one transaction, so what
// it holds then is what a kill would have left.
class KilledCopy : public SmcObserver {
 public:
  KilledCopy(std::string path, int wave, int batches)
      : path_(std::move(path)), wave_(wave), batches_(batches) {}
  void SetRunHistory(const std::string& path) { run_history_ = path; }
  void OnWaveStart(const WaveRecord& wave) override {
    if (!store_) {
      store_.emplace(
          HistoryStore::Create(path_, HistoryStore::Open(run_history_, true).LoadMetadata()));
      killed_ = batches_ == 0;
    }
    if (!killed_) store_->OnWaveStart(wave);
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    if (killed_) return;
    store_->OnBatch(progress, accepted);
    if (progress.wave == wave_ && progress.accepted > 0 && ++seen_ == batches_) {
      killed_ = true;
      at_ = progress;
    }
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    if (!killed_) store_->OnWaveEnd(wave);
  }
  // Closes the copy (as the killed process's exit would) and says where it stopped.
  BatchProgress Close() {
    store_.reset();
    return at_;
  }
  bool killed() const { return killed_; }

 private:
  std::string path_, run_history_;
  int wave_, batches_, seen_ = 0;
  bool killed_ = false;
  BatchProgress at_;
  std::optional<HistoryStore> store_;
};

class ExperimentsResume : public ::testing::Test {
 protected:
  ExperimentsResume() : dir_("e2e-experiments-resume") {}

  static std::string Config(const std::string& limits = "") {
    return ExperimentsConfig(
        {kRight, kLeft7Hz, kMid},
        "seed = 7\nwaves = 3\naccepted_per_wave = 24\nbatch_size = 4\nthreads = 2\n"
        "estimator = \"importance\"\n" +
            limits);
  }

  // Runs the three-experiment config (two plate models) uninterrupted into whole/, recording `copy`
  // alongside (if given).
  void RunWhole(KilledCopy* copy) {
    for (const TinyExperiment& x : {kRight, kLeft7Hz, kMid}) WriteTentData(dir_.path(), x);
    std::ofstream(dir_ / "run.toml") << Config();
    services::RunRequest request;
    request.config_path = dir_ / "run.toml";
    request.output_directory = dir_ / "whole";
    request.report = false;
    request.on_history_path = [&](const std::string& path) {
      if (copy != nullptr) copy->SetRunHistory(path);
    };
    const services::RunOutcome outcome = services::RunCalibration(request, copy);
    whole_ = outcome.history_path;
    ASSERT_EQ(outcome.history.waves.size(), 3u);
  }

  // Resumes `killed` through the CLI (one thread: the run had two; `options` added) and compares
  // it with the uninterrupted run.
  void ExpectResumesToTheWholeRun(const std::string& killed,
                                  const std::vector<std::string>& options = {}) {
    std::vector<std::string> args = {"resume", killed, "--no-report", "-q", "-j", "1"};
    args.insert(args.end(), options.begin(), options.end());
    const auto r = RunCli(args, dir_.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const RunHistory whole = HistoryStore::Open(whole_, true).LoadHistory();
    const RunHistory resumed = HistoryStore::Open(killed, true).LoadHistory();
    std::string where;
    EXPECT_TRUE(SameHistory(whole, resumed, &where)) << where;
    // SameHistory's contract, spelled out for what the experiments add: every wave's thresholds
    // (one per experiment's component) and each particle's distances.
    ASSERT_EQ(resumed.waves.size(), whole.waves.size());
    for (std::size_t w = 0; w < whole.waves.size(); ++w) {
      EXPECT_EQ(resumed.waves[w].thresholds, whole.waves[w].thresholds) << "wave " << w;
      EXPECT_EQ(resumed.waves[w].thresholds.size(), 3u);
      ASSERT_EQ(resumed.waves[w].particles.size(), whole.waves[w].particles.size());
      for (std::size_t i = 0; i < whole.waves[w].particles.size(); ++i) {
        EXPECT_EQ(resumed.waves[w].particles[i].theta.bits, whole.waves[w].particles[i].theta.bits);
        EXPECT_EQ(resumed.waves[w].particles[i].distance, whole.waves[w].particles[i].distance);
        EXPECT_EQ(resumed.waves[w].particles[i].weight, whole.waves[w].particles[i].weight);
      }
    }
    const RunMetadata after = HistoryStore::Open(killed, true).LoadMetadata();
    EXPECT_EQ(after.status, RunStatus::kFinished);
    EXPECT_EQ(after.resume_count, 1);
    ASSERT_EQ(after.experiments.size(), 3u);
    EXPECT_EQ(after.experiments[0].name, "right");
    EXPECT_EQ(after.experiments[1].name, "left.7Hz");
    EXPECT_EQ(after.experiments[2].name, "mid_2cm");
    const auto verified = RunCli({"verify", killed}, dir_.path());
    EXPECT_EQ(verified.exit_code, 0) << verified.out << verified.err;
  }

  ScratchDir dir_;
  std::string whole_;
};

TEST_F(ExperimentsResume, KilledMidWaveResumesToTheUninterruptedHistory) {
  KilledCopy copy(dir_ / "killed.sqlite", /*wave=*/1, /*batches=*/2);
  RunWhole(&copy);
  ASSERT_TRUE(copy.killed());
  const BatchProgress at = copy.Close();
  ASSERT_GT(at.accepted, 0);
  ASSERT_LT(at.accepted, at.accepted_needed) << "mid-wave";
  const ResumePoint point = HistoryStore::Open(dir_ / "killed.sqlite", true).LoadResumePoint();
  ASSERT_TRUE(point.has_partial);
  EXPECT_EQ(point.partial_wave, 1);
  EXPECT_EQ(static_cast<std::int64_t>(point.partial_accepted.size()), at.accepted);
  // The stored experiments are what resume rebuilds the joint distance from.
  const RunMetadata m = HistoryStore::Open(dir_ / "killed.sqlite", true).LoadMetadata();
  ASSERT_EQ(m.experiments.size(), 3u);
  EXPECT_EQ(m.experiments[1].outputs, 91);
  EXPECT_EQ(m.experiments[2].outputs, 46);
  EXPECT_EQ(m.experiments[1].measured, 9);
  EXPECT_EQ(m.experiments[2].measured, 8);
  ASSERT_EQ(m.distance_components.size(), 3u);
  EXPECT_EQ(m.distance_components[0].name, "right/least_squares[63-87cm]");
  EXPECT_EQ(m.distance_components[1].name, "left.7Hz/least_squares[3-27cm]");
  EXPECT_EQ(m.distance_components[2].name, "mid_2cm/least_squares[33-54cm]");
  EXPECT_EQ(m.status, RunStatus::kRunning);
  ExpectResumesToTheWholeRun(dir_ / "killed.sqlite");
}

TEST_F(ExperimentsResume, KilledBeforeTheFirstBatchResumesToTheUninterruptedHistory) {
  KilledCopy copy(dir_ / "started.sqlite", /*wave=*/0, /*batches=*/0);
  RunWhole(&copy);
  copy.Close();
  const ResumePoint point = HistoryStore::Open(dir_ / "started.sqlite", true).LoadResumePoint();
  EXPECT_TRUE(point.completed.empty());
  EXPECT_FALSE(point.has_partial);
  ExpectResumesToTheWholeRun(dir_ / "started.sqlite");
}

// Stopped by its budget inside the last wave (through the CLI), then resumed with a larger one.
TEST_F(ExperimentsResume, ABudgetStopResumesWithALargerBudgetToTheUninterruptedHistory) {
  RunWhole(nullptr);
  const auto total = HistoryStore::Open(whole_, true).LoadHistory().summary.simulations;
  std::ofstream(dir_ / "stopped.toml")
      << Config("max_simulations = " + std::to_string(total - 5) + "\n");
  const auto r = RunCli({"run", dir_ / "stopped.toml", "--no-report", "-q", "-o", dir_ / "stopped"},
                        dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string stopped = dir_ / "stopped/history.sqlite";
  const RunMetadata m = HistoryStore::Open(stopped, true).LoadMetadata();
  ASSERT_EQ(m.termination, "budget_exhausted") << m.summary_message;
  ASSERT_EQ(HistoryStore::Open(stopped, true).LoadResumePoint().partial_wave, 2);
  ExpectResumesToTheWholeRun(stopped, {"--max-simulations", "100000"});
}

}  // namespace
}  // namespace combabc::testing
