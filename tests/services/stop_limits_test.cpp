// The stop limits a resume sets and the check that decides whether a history may be continued
// (src/services/steps/run_steps.*), in the CLI's words and in Python's.
#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "combabc/core/enum_names.hpp"
#include "combabc/core/error.hpp"
#include "services/steps/run_steps.hpp"

namespace combabc::services {
namespace {

using Limits = std::vector<std::pair<std::string, std::string>>;

TEST(StopLimits, GivenOverrideRecordedAndUnknownKeysAreSkipped) {
  SmcOptions options;
  StopLimits given;
  given.max_simulations = 5000;
  given.num_waves = 7;
  const Limits recorded = {
      {"max_simulations", "100"}, {"min_acceptance_rate", "0.05"}, {"from_the_future", "1"}};
  const Limits set = ApplyStopLimits(recorded, given, options);
  EXPECT_EQ(set,
            (Limits{{"max_simulations", "5000"}, {"min_acceptance_rate", "0.05"}, {"waves", "7"}}));
  EXPECT_EQ(options.max_simulations, 5000);
  EXPECT_DOUBLE_EQ(options.min_acceptance_rate, 0.05);
  EXPECT_EQ(options.num_waves, 7);
}

TEST(StopLimits, AnInvalidLimitIsAUsageErrorNamingTheField) {
  SmcOptions options;
  StopLimits given;
  given.min_acceptance_rate = 2.0;
  try {
    ApplyStopLimits({}, given, options);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_STREQ(e.what(), "resume: SmcOptions::min_acceptance_rate = 2.000000; must be in [0, 1]");
  }
}

RunMetadata Finished(std::string_view termination) {
  RunMetadata m;
  m.status = RunStatus::kFinished;
  m.termination = std::string(termination);
  return m;
}

std::string Refusal(const RunMetadata& m, OptionNames names) {
  try {
    CheckResumable(m, {}, names, "run.db");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    return e.what();
  }
  return "resumable";
}

TEST(StopLimits, CheckResumableSaysWhatToDoNext) {
  RunMetadata running;
  EXPECT_FALSE(CheckResumable(running, {}, OptionNames::kCli, "run.db"));
  EXPECT_TRUE(CheckResumable(
      Finished(ToString(Termination::kBudgetExhausted)), {}, OptionNames::kCli, "run.db"));
  StopLimits more;
  more.num_waves = 9;
  EXPECT_TRUE(CheckResumable(
      Finished(ToString(Termination::kMaxWaves)), more, OptionNames::kCli, "run.db"));
  EXPECT_EQ(
      Refusal(Finished(ToString(Termination::kMaxWaves)), OptionNames::kCli),
      "run.db: the run has already finished (max_waves); nothing to resume. Use 'combabc report' "
      "or 'combabc export'; or give it more waves: --waves N");
  EXPECT_EQ(
      Refusal(Finished(ToString(Termination::kMaxWaves)), OptionNames::kPython),
      "run.db: the run has already finished (max_waves); nothing to resume: give it more waves "
      "with waves=N");
}

}  // namespace
}  // namespace combabc::services
