// The joint ABC posterior of two experiments on the tiny sensor (3 + 3 clamps: 64 configurations),
// data simulated at a known configuration with a 5 % ripple. Exact: `combabc enumerate` of the
// two-experiment config accepts exactly the configurations that both single-experiment configs
// accept at the same thresholds (the product of the experiments' acceptance), with the same
// distances. Sampled: `combabc run` (importance estimator, list schedules ending at those
// thresholds) accepts only those configurations and its marginals agree with the exact ones
// within 5 Monte-Carlo standard errors. Fixed seed: deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "combabc/config/config.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/services/simulate.hpp"
#include "tiny_experiments.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr char kTruth[] = "101101";
constexpr int kConfigurations = 64;

// Each load sees the clamps at its end of the plate: with its data alone the other end's clamps
// stay free to vary. The final thresholds (0.07, 0.6) lie in wide gaps of each experiment's
// distances (about 1e-3 | 0.13 and 0.18 | 1.0 here).
const TinyExperiment kRight =
    Experiment("right", 0.75, 5.0, 0.63, 0.87, "", "[1.2, 0.6, 0.2, 0.07]");
const TinyExperiment kLeft = Experiment("left", 0.15, 5.0, 0.03, 0.27, "", "[2.0, 1.2, 0.8, 0.6]");

std::string Sampler(int accepted) {
  return "seed = 11\nwaves = 4\naccepted_per_wave = " + std::to_string(accepted) +
         "\nestimator = \"importance\"\nthreads = 2\n";
}

std::string BitString(const std::vector<std::uint8_t>& bits) {
  std::string s;
  for (std::uint8_t b : bits) s += b ? '1' : '0';
  return s;
}

// Each experiment's data: the nominal model at kTruth (raw metres; the data are normalised as
// the simulation is) every 3 cm of its window, times 1 + 0.05 sin(1.7 k).
void WriteSimulatedData(const fs::path& dir, const std::vector<TinyExperiment>& experiments) {
  std::ofstream(dir / "truth.toml") << ExperimentsConfig(experiments, Sampler(10));
  const services::NominalSimulator model(LoadConfig((dir / "truth.toml").string()),
                                         (dir / "work").string());
  const std::vector<double> w = model.Simulate(model.ParseBits(kTruth));
  std::size_t begin = 0;
  for (std::size_t e = 0; e < experiments.size(); ++e) {
    const std::vector<double>& at = model.config().experiments[e].output_coordinates;
    int k = 0;
    WriteExperimentData(dir, experiments[e], [&](double position) {
      for (std::size_t i = 0; i < at.size(); ++i) {
        if (std::abs(at[i] - position) < 1e-9) {
          return w[begin + i] * (1 + 0.05 * std::sin(1.7 * k++));
        }
      }
      ADD_FAILURE() << "no output at " << position;
      return 0.0;
    });
    begin += at.size();
  }
}

// The accepted configurations of an enumeration's history, with their distances.
std::map<std::string, std::vector<double>> Accepted(const WaveRecord& wave) {
  std::map<std::string, std::vector<double>> accepted;
  for (const Particle& p : wave.particles) accepted[BitString(p.theta.bits)] = p.distance;
  return accepted;
}

WaveRecord Enumerated(const fs::path& dir, const std::string& config) {
  const std::string out = (dir / (config + ".enum")).string();
  const auto r = RunCli(
      {"enumerate", (dir / (config + ".toml")).string(), "--no-report", "-q", "-o", out}, dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const RunHistory h = HistoryStore::Open(out + "/history.sqlite", true).LoadHistory();
  EXPECT_EQ(h.waves.size(), 1u);
  if (h.waves.empty()) return {};
  EXPECT_EQ(h.waves[0].candidates, kConfigurations) << config;
  EXPECT_EQ(h.waves[0].accepted, static_cast<std::int64_t>(h.waves[0].particles.size())) << config;
  return h.waves[0];
}

TEST(ExperimentsPosterior, IsTheProductOfTheExperimentsAcceptanceAndSmcSamplesIt) {
  TempFolder dir("e2e-experiments-posterior");
  WriteSimulatedData(dir.path(), {kRight, kLeft});
  const int accepted = 1000;
  std::ofstream(dir / "joint.toml") << ExperimentsConfig({kRight, kLeft}, Sampler(accepted));
  std::ofstream(dir / "right.toml") << SingleExperimentConfig(kRight, Sampler(accepted));
  std::ofstream(dir / "left.toml") << SingleExperimentConfig(kLeft, Sampler(accepted));

  // Exact, at the config's final thresholds (0.07, 0.6).
  const WaveRecord joint = Enumerated(dir.path(), "joint");
  const WaveRecord right = Enumerated(dir.path(), "right");
  const WaveRecord left = Enumerated(dir.path(), "left");
  ASSERT_EQ(joint.thresholds, (std::vector<double>{0.07, 0.6}));
  const auto both = Accepted(joint), by_right = Accepted(right), by_left = Accepted(left);
  std::set<std::string> intersection;
  for (const auto& [bits, d] : by_right) {
    if (by_left.count(bits)) intersection.insert(bits);
  }
  std::set<std::string> joint_set;
  for (const auto& [bits, d] : both) joint_set.insert(bits);
  EXPECT_EQ(joint_set, intersection);
  // Each experiment constrains what the other leaves free: the product is strictly smaller.
  EXPECT_LT(both.size(), by_right.size());
  EXPECT_LT(both.size(), by_left.size());
  ASSERT_GE(both.size(), 4u);
  EXPECT_TRUE(both.count(kTruth));
  for (const auto& [bits, d] : both) {
    ASSERT_EQ(d.size(), 2u);
    EXPECT_EQ(d[0], by_right.at(bits).at(0)) << bits;
    EXPECT_EQ(d[1], by_left.at(bits).at(0)) << bits;
  }
  // A uniform prior: the exact posterior is uniform over the accepted configurations.
  std::vector<double> exact(6, 0.0);
  for (const auto& [bits, d] : both) {
    for (int k = 0; k < 6; ++k) exact[k] += (bits[k] == '1') / static_cast<double>(both.size());
  }
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(joint.marginals_importance[k], exact[k], 1e-12) << k;

  // Sampled.
  const auto r =
      RunCli({"run", dir / "joint.toml", "--no-report", "-q", "-o", dir / "smc"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string history = dir / "smc/history.sqlite";
  EXPECT_EQ(HistoryStore::Open(history, true).LoadMetadata().termination, "target_reached");
  const RunHistory h = HistoryStore::Open(history, true).LoadHistory();
  ASSERT_EQ(h.waves.size(), 4u);
  const WaveRecord& last = h.waves.back();
  ASSERT_EQ(last.thresholds, joint.thresholds);
  ASSERT_EQ(last.particles.size(), static_cast<std::size_t>(accepted));
  for (const Particle& p : last.particles) {
    const auto it = both.find(BitString(p.theta.bits));
    ASSERT_NE(it, both.end()) << BitString(p.theta.bits) << " is not accepted by both";
    EXPECT_EQ(p.distance, it->second) << it->first;
  }
  EXPECT_EQ(last.distinct, static_cast<std::int64_t>(both.size())) << "every one is visited";
  for (int k = 0; k < 6; ++k) {
    const double p = exact[k];
    // A floor for exact 0/1 marginals, whose binomial error is 0.
    const double bound = 5.0 * std::sqrt(p * (1.0 - p) / last.ess) + 2e-3;
    EXPECT_NEAR(last.marginals_importance[k], p, bound) << "bit " << k << ", ESS " << last.ess;
  }
}

// Adding an experiment to a finished run (`combabc run --from`, docs/algorithm.md "Adding data to
// a finished run"): the right experiment's finished run, then the joint config started from it,
// samples the same exact joint posterior as above; a config that changed the finished run's data
// or adds no experiment is refused (exit 78) and writes nothing.
TEST(ExperimentsPosterior, AddingAnExperimentToAFinishedRunSamplesTheJointPosterior) {
  TempFolder dir("e2e-experiments-from");
  WriteSimulatedData(dir.path(), {kRight, kLeft});
  // Longer lists to the same final thresholds: a move wave may take a shorter step than its
  // list's to keep its ESS, and catches up in the waves after.
  TinyExperiment right = kRight;
  TinyExperiment left = kLeft;
  right.threshold = "[1.2, 0.6, 0.3, 0.2, 0.15, 0.1, 0.07, 0.07]";
  left.threshold = "[2.0, 1.2, 1.0, 0.8, 0.7, 0.6, 0.6, 0.6]";
  const std::string sampler =
      "seed = 11\nwaves = 8\naccepted_per_wave = 500\nthreads = 2\nmethod = \"resample_move\"\n";
  std::ofstream(dir / "joint.toml") << ExperimentsConfig({right, left}, sampler);
  std::ofstream(dir / "right.toml") << ExperimentsConfig({right}, sampler);
  const WaveRecord joint = Enumerated(dir.path(), "joint");
  const auto both = Accepted(joint);
  auto r =
      RunCli({"run", dir / "right.toml", "--no-report", "-q", "-o", dir / "right"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string finished = dir / "right/history.sqlite";
  r = RunCli(
      {"run", dir / "joint.toml", "--no-report", "-q", "-o", dir / "added", "--from", finished},
      dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RunHistory h = HistoryStore::Open(dir / "added/history.sqlite", true).LoadHistory();
  ASSERT_GE(h.waves.size(), 2u);
  const RunHistory first = HistoryStore::Open(finished, true).LoadHistory();
  EXPECT_EQ(h.waves.front().candidates,
            static_cast<std::int64_t>(first.waves.back().particles.size()))
      << "wave 0 re-simulates the finished run's last wave";
  const WaveRecord& last = h.waves.back();
  ASSERT_EQ(last.thresholds, joint.thresholds);
  ASSERT_TRUE(last.moves.has_value());
  for (const Particle& p : last.particles) {
    ASSERT_TRUE(both.count(BitString(p.theta.bits))) << BitString(p.theta.bits);
  }
  for (int k = 0; k < 6; ++k) {
    double exact = 0.0;
    for (const auto& [bits, d] : both) exact += (bits[k] == '1') / static_cast<double>(both.size());
    // Moved particles are correlated: a quarter of the particle count as the effective size.
    const double bound = 5.0 * std::sqrt(exact * (1.0 - exact) / (last.ess / 4.0)) + 2e-3;
    EXPECT_NEAR(last.marginals_importance[k], exact, bound) << "bit " << k;
  }
  // No new experiment: refused, nothing written.
  r = RunCli(
      {"run", dir / "right.toml", "--no-report", "-q", "-o", dir / "same", "--from", finished},
      dir.path());
  EXPECT_EQ(r.exit_code, 78) << r.err;
  EXPECT_NE(r.err.find("adds no experiment"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(finished), std::string::npos) << r.err;
  // The finished run's experiment with other data: refused.
  WriteExperimentData(dir.path(), right, [](double p) { return 1.0 - std::abs(p - 0.5); });
  r = RunCli(
      {"run", dir / "joint.toml", "--no-report", "-q", "-o", dir / "other", "--from", finished},
      dir.path());
  EXPECT_EQ(r.exit_code, 78) << r.err;
  EXPECT_NE(r.err.find("measured data differ"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "other/history.sqlite"));
}

}  // namespace
}  // namespace combabc::testing
