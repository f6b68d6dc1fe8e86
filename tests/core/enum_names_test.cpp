// Every enum's name table (core/enum_names.hpp): names are unique, each value has exactly one
// name, and ToString / ParseEnum are inverse. A duplicated or missing row fails here.
#include "combabc/core/enum_names.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/distances/distance.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/metrics/metric_component.hpp"
#include "combabc/plate/assembly/plate.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/samplers/smc_options.hpp"
#include "combabc/schedules/tempering_schedule.hpp"
#include "combabc/schedules/threshold_schedule.hpp"

namespace combabc {
namespace {

template <typename E>
class EnumNamesTest : public ::testing::Test {};

using AllEnums = ::testing::Types<ErrorKind,
                                  LengthUnit,
                                  ComponentKind,
                                  RunStatus,
                                  MetricType,
                                  MetricPreset,
                                  plate::Support,
                                  Termination,
                                  Estimator,
                                  TemperingKind,
                                  TemperingForm,
                                  ThresholdKind>;
TYPED_TEST_SUITE(EnumNamesTest, AllEnums);

TYPED_TEST(EnumNamesTest, NamesAreUniqueAndRoundTrip) {
  std::set<std::string> names;
  std::set<int> values;
  for (const auto& [value, name] : EnumNames<TypeParam>::kNames) {
    EXPECT_TRUE(names.insert(name).second) << "duplicate name " << name;
    EXPECT_TRUE(values.insert(static_cast<int>(value)).second) << "value named twice: " << name;
    EXPECT_STREQ(ToString(value), name);
    EXPECT_EQ(ParseEnum<TypeParam>(name), value);
    EXPECT_NE(EnumChoices<TypeParam>().find("\"" + std::string(name) + "\""), std::string::npos);
  }
  // Enumerators are declared densely from 0, so the table covers them all when its values do.
  EXPECT_EQ(*values.begin(), 0);
  EXPECT_EQ(*values.rbegin(), static_cast<int>(values.size()) - 1);
  EXPECT_EQ(ParseEnum<TypeParam>("no such name"), std::nullopt);
  EXPECT_EQ(ParseEnum<TypeParam>(""), std::nullopt);
}

TEST(EnumNames, ChoicesListEveryNameInTableOrder) {
  EXPECT_EQ(EnumChoices<Estimator>(), "\"paper\", \"importance\"");
  EXPECT_EQ(EnumChoices<plate::Support>(), "\"free\", \"simply_supported\", \"clamped\"");
}

}  // namespace
}  // namespace combabc
