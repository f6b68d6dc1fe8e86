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

}  // namespace
}  // namespace combabc
