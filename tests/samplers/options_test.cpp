#include "combabc/samplers/smc_options.hpp"

#include <gtest/gtest.h>

#include <functional>

#include "combabc/core/error.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

struct Case {
  const char* name;
  std::function<void(SmcOptions&)> mutate;
  const char* message;
};

TEST(SmcOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SmcOptions{}.IsValid(&why)) << why;
}

TEST(SmcOptions, EachInvalidOptionIsRejectedWithItsMessage) {
  const std::vector<Case> cases = {
      {"waves", [](SmcOptions& o) { o.num_waves = 0; }, "SmcOptions::num_waves = 0; must be >= 1"},
      {"accepted",
       [](SmcOptions& o) { o.accepted_per_wave = -3; },
       "SmcOptions::accepted_per_wave = -3; must be >= 1"},
      {"threads",
       [](SmcOptions& o) { o.threads = -1; },
       "SmcOptions::threads = -1; must be in [0, 4096] (0 = all cores)"},
      {"budget",
       [](SmcOptions& o) { o.max_simulations = -5; },
       "SmcOptions::max_simulations = -5; must be >= 0"},
      {"rate",
       [](SmcOptions& o) { o.min_acceptance_rate = 1.5; },
       "SmcOptions::min_acceptance_rate = 1.500000; must be in [0, 1]"},
      {"wall",
       [](SmcOptions& o) { o.max_wall_time_s = -1; },
       "SmcOptions::max_wall_time_s = -1.000000; must be finite and >= 0"},
      {"batch",
       [](SmcOptions& o) { o.batch_size = -2; },
       "SmcOptions::batch_size = -2; must be >= 0 (0 = automatic)"},
      {"quantile",
       [](SmcOptions& o) {
         o.thresholds.resize(1);
         o.thresholds[0].quantile = 0.0;
       },
       "SmcOptions::thresholds[0].quantile = 0.000000; must be in (0, 1]"},
      {"target",
       [](SmcOptions& o) {
         o.thresholds.resize(1);
         o.thresholds[0].initial = 1.0;
         o.thresholds[0].target = 2.0;
       },
       "SmcOptions::thresholds[0].target = 2.000000 > initial = 1.000000; the schedule must "
       "decrease"},
      {"list length",
       [](SmcOptions& o) {
         o.thresholds.resize(1);
         o.thresholds[0].kind = ThresholdKind::kList;
         o.thresholds[0].values = {3, 2};
       },
       "SmcOptions::thresholds[0].values has 2 entries; must have one per wave (num_waves = 5)"},
      {"list negative",
       [](SmcOptions& o) {
         o.thresholds.resize(1);
         o.thresholds[0].kind = ThresholdKind::kList;
         o.thresholds[0].values = {3, 2, 1, 0, -1};
       },
       "SmcOptions::thresholds[0].values[4] = -1.000000; must be >= 0"},
      {"phi0",
       [](SmcOptions& o) { o.tempering.phi0 = 1.2; },
       "SmcOptions::tempering.phi0 = 1.200000; must be in [0, 1]"},
      {"phi list",
       [](SmcOptions& o) {
         o.tempering.kind = TemperingKind::kList;
         o.tempering.values = {0.5};
       },
       "SmcOptions::tempering.values has 1 entries; must have 4 (one per wave after the first)"},
  };
  for (const auto& c : cases) {
    SmcOptions o;
    c.mutate(o);
    std::string why;
    EXPECT_FALSE(o.IsValid(&why)) << c.name;
    EXPECT_EQ(why, c.message) << c.name;
  }
}

TEST(SmcOptions, RunRejectsInvalidOptionsBeforeAnyWork) {
  const ParameterSpace space(BinarySpace::Independent(4));
  testing::IdentitySimulator sim(4);
  testing::WeightedL1Distance dist({1, 0, 1, 0}, {1, 1, 1, 1});
  SmcOptions o;
  o.accepted_per_wave = 0;
  try {
    RunCombinatorialSmc({&space, &sim, &dist}, o);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    EXPECT_STREQ(e.what(), "SmcOptions::accepted_per_wave = 0; must be >= 1");
  }
  o = SmcOptions{};
  o.thresholds.resize(2);  // the distance has one threshold component
  try {
    RunCombinatorialSmc({&space, &sim, &dist}, o);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "SmcOptions::thresholds");
  }
  EXPECT_THROW(RunCombinatorialSmc({&space, nullptr, &dist}, SmcOptions{}), Error);
}

TEST(Enums, RoundTripThroughStrings) {
  for (auto e : {Estimator::kPaper, Estimator::kImportance}) {
    EXPECT_EQ(ParseEnum<Estimator>(ToString(e)), e);
  }
  for (auto k : {ThresholdKind::kList, ThresholdKind::kQuantile}) {
    EXPECT_EQ(ParseEnum<ThresholdKind>(ToString(k)), k);
  }
  for (auto t : {Termination::kTargetReached,
                 Termination::kMaxWaves,
                 Termination::kBudgetExhausted,
                 Termination::kAcceptanceRateTooLow,
                 Termination::kWallTimeExceeded,
                 Termination::kInterrupted}) {
    EXPECT_EQ(ParseEnum<Termination>(ToString(t)), t);
  }
  EXPECT_EQ(ParseEnum<Estimator>("weighted"), std::nullopt);
}

}  // namespace
}  // namespace combabc
