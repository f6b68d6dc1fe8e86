// [sampler] accepted_per_wave as a list (n_t per wave) and the [metric] threshold schedules driven
// by acceptance rate or ESS, and the weighted quantile: what they set, and their one-line errors.
#include <gtest/gtest.h>

#include <string>

#include "combabc/config/config.hpp"
#include "config_error.hpp"

namespace combabc {
namespace {

using testing::ConfigErrorOf;

const std::string kMinimal =
    "[data]\n"
    "csv = \"p.csv\"\n"
    "[metric]\n"
    "preset = \"area\"\n";

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(ScheduleConfig, AcceptedPerWaveTakesOneNumberPerWave) {
  const CalibrationConfig c = ParseConfig(
      kMinimal + "[sampler]\nwaves = 3\naccepted_per_wave = [2000, 500, 800]\n", "dir/run.toml");
  EXPECT_EQ(c.smc.accepted_by_wave, (std::vector<int>{2000, 500, 800}));
  EXPECT_EQ(c.smc.AcceptedIn(2), 800);
  EXPECT_TRUE(ParseConfig(kMinimal + "[sampler]\naccepted_per_wave = 300\n", "dir/run.toml")
                  .smc.accepted_by_wave.empty());
  std::string e =
      ConfigErrorOf(kMinimal + "[sampler]\nwaves = 3\naccepted_per_wave = [2000, 500]\n");
  EXPECT_TRUE(Contains(e,
                       "sampler.accepted_per_wave: has 2 entries; a list needs one per wave "
                       "(waves = 3)"))
      << e;
  e = ConfigErrorOf(kMinimal + "[sampler]\nwaves = 2\naccepted_per_wave = [2000, 0]\n");
  EXPECT_TRUE(Contains(e, "sampler.accepted_per_wave[1]: must be an integer in [1, 1000000000]"))
      << e;
  e = ConfigErrorOf(kMinimal + "[sampler]\nwaves = 2\naccepted_per_wave = [2000, 1.5]\n");
  EXPECT_TRUE(Contains(e, "sampler.accepted_per_wave[1]")) << e;
}

TEST(ScheduleConfig, AdaptiveSchedulesByAcceptanceRateEssOrWeightedQuantile) {
  auto schedule = [](const std::string& keys) {
    return ParseConfig(kMinimal + keys, "dir/run.toml").smc.thresholds.at(0);
  };
  ThresholdSchedule s = schedule("acceptance_rate = 0.05\ntarget = 0.1\n");
  EXPECT_EQ(s.kind, ThresholdKind::kAcceptance);
  EXPECT_EQ(s.acceptance_rate, 0.05);
  EXPECT_EQ(s.target, 0.1);
  s = schedule("ess_fraction = 0.6\n");
  EXPECT_EQ(s.kind, ThresholdKind::kEss);
  EXPECT_EQ(s.ess_fraction, 0.6);
  s = schedule("quantile = 0.3\nweighted = true\n");
  EXPECT_EQ(s.kind, ThresholdKind::kQuantile);
  EXPECT_TRUE(s.weighted);
  EXPECT_FALSE(schedule("quantile = 0.3\n").weighted);
}

TEST(ScheduleConfig, AdaptiveScheduleErrorsNameTheKey) {
  std::string e = ConfigErrorOf(kMinimal + "acceptance_rate = 0\n");
  EXPECT_TRUE(Contains(e, "metric.acceptance_rate: must be in (0, 1]")) << e;
  e = ConfigErrorOf(kMinimal + "ess_fraction = 1\n");
  EXPECT_TRUE(Contains(e, "metric.ess_fraction: must be in (0, 1)")) << e;
  e = ConfigErrorOf(kMinimal + "quantile = 0.5\nacceptance_rate = 0.1\n");
  EXPECT_TRUE(Contains(e,
                       "metric.acceptance_rate: give one of quantile, acceptance_rate and "
                       "ess_fraction"))
      << e;
  e = ConfigErrorOf(kMinimal + "ess_fraction = 0.5\nweighted = true\n");
  EXPECT_TRUE(Contains(e, "metric.weighted: only used by the quantile schedule")) << e;
  e = ConfigErrorOf(kMinimal + "threshold = [3.0, 2.0, 1.0, 0.5, 0.2]\nacceptance_rate = 0.1\n");
  EXPECT_TRUE(Contains(e, "metric.threshold: give either threshold = [...] or the adaptive keys"))
      << e;
}

// [sampler] method and [sampler.moves]: every MoveOptions key set, the defaults without them, and
// each mistake located at its key (a move option in a rejection run too).
TEST(ScheduleConfig, SamplerMethodAndMoveOptions) {
  const std::string moves = kMinimal + "[sampler]\nmethod = \"resample_move\"\n[sampler.moves]\n";
  const CalibrationConfig c =
      ParseConfig(moves +
                      "ess_fraction = 0.7\nstay_probability = 0.05\nmax_rounds = 12\n"
                      "independent_share = 0.25\nmin_survivor_fraction = 0.1\n",
                  "dir/run.toml");
  EXPECT_EQ(c.smc.method, SamplerMethod::kResampleMove);
  EXPECT_EQ(c.smc.moves.ess_fraction, 0.7);
  EXPECT_EQ(c.smc.moves.stay_probability, 0.05);
  EXPECT_EQ(c.smc.moves.max_rounds, 12);
  EXPECT_EQ(c.smc.moves.independent_share, 0.25);
  EXPECT_EQ(c.smc.moves.min_survivor_fraction, 0.1);
  const MoveOptions defaults;
  const CalibrationConfig plain = ParseConfig(kMinimal, "dir/run.toml");
  EXPECT_EQ(plain.smc.method, SamplerMethod::kRejection);
  EXPECT_EQ(plain.smc.moves.max_rounds, defaults.max_rounds);
  EXPECT_EQ(
      ParseConfig(kMinimal + "[sampler]\nmethod = \"rejection\"\n", "dir/run.toml").smc.method,
      SamplerMethod::kRejection);

  for (const std::string bad : {"ess_fraction = 1",
                                "stay_probability = 0",
                                "min_survivor_fraction = 1.5",
                                "ess_fraction = -0.5"}) {
    const std::string key = bad.substr(0, bad.find(' '));
    EXPECT_EQ(ConfigErrorOf(moves + bad + "\n"),
              "dir/run.toml:8: sampler.moves." + key + ": must be in (0, 1)")
        << bad;
  }
  std::string e = ConfigErrorOf(moves + "max_rounds = 0\n");
  EXPECT_EQ(e.rfind("dir/run.toml:8: sampler.moves.max_rounds: is 0; must be in [1, 10000]", 0), 0u)
      << e;
  e = ConfigErrorOf(moves + "independent_share = 2\n");
  EXPECT_EQ(e.rfind("dir/run.toml:8: sampler.moves.independent_share: is 2", 0), 0u) << e;
  e = ConfigErrorOf(moves + "rounds = 3\n");
  EXPECT_EQ(e.rfind("dir/run.toml:8: sampler.moves.rounds: unknown key", 0), 0u) << e;
  e = ConfigErrorOf(kMinimal + "[sampler]\nmethod = \"mcmc\"\n");
  EXPECT_EQ(e.rfind("dir/run.toml:6: sampler.method: unknown sampler method 'mcmc'; expected "
                    "one of \"rejection\", \"resample_move\"",
                    0),
            0u)
      << e;
  // SmcOptions::IsValid's complaint about the method is reported at its key.
  e = ConfigErrorOf(kMinimal + "[sampler]\nestimator = \"paper\"\nmethod = \"resample_move\"\n");
  EXPECT_EQ(e.rfind("dir/run.toml:7: sampler.method: ", 0), 0u) << e;
  EXPECT_NE(e.find("estimator = importance"), std::string::npos) << e;
  // Move options in a rejection run (by default or said) would be silently unused.
  for (const std::string method : {"", "method = \"rejection\"\n"}) {
    std::string text = kMinimal + "[sampler]\n";
    text += method;
    text += "[sampler.moves]\nmax_rounds = 5\n";
    e = ConfigErrorOf(text);
    EXPECT_EQ(e.rfind("dir/run.toml:" + std::to_string(method.empty() ? 6 : 7) +
                          ": sampler.moves: move options apply to resample-move runs only",
                      0),
              0u)
        << e;
  }
}

}  // namespace
}  // namespace combabc
