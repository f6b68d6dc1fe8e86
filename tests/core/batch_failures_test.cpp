// BatchFailures (core/batch_failures.hpp): the per-candidate failure rows that simulators and
// distances write and the samplers read (the failures themselves:
// tests/samplers/failures_test.cpp).
#include "combabc/core/batch_failures.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace combabc {
namespace {

TEST(Failures, ALongReasonIsCutAtACharacterBoundary) {
  std::vector<std::uint8_t> status(2, 0);
  std::vector<char> reasons(2 * kFailureReasonBytes, 'x');
  BatchFailures failures{std::span(status), std::span(reasons)};
  std::string reason(kFailureReasonBytes - 2, 'a');
  reason += "\xC3\xA9\xC3\xA9";  // two two-byte characters across the limit
  failures.Fail(1, reason);
  EXPECT_FALSE(failures.failed(0));
  ASSERT_TRUE(failures.failed(1));
  EXPECT_EQ(failures.reason(1), std::string(kFailureReasonBytes - 2, 'a'));
  failures.Fail(0, "short");
  EXPECT_EQ(failures.reason(0), "short");
}

}  // namespace
}  // namespace combabc
