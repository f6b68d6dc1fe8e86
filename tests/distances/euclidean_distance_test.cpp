// EuclideanDistance (the default distance of a problem written in Python) and the batch form every
// Distance has (Distance::EvaluateBatch, what the samplers call).
#include "combabc/distances/euclidean_distance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "support/test_support.hpp"

namespace combabc {
namespace {

using testing::ExpectNear;

TEST(EuclideanDistance, IsTheTwoNormOfTheDifferenceInOneThresholdComponent) {
  const EuclideanDistance distance({1.0, 2.0, 3.0});
  const std::vector<DistanceComponent> components = distance.components();
  ASSERT_EQ(components.size(), 1u);
  EXPECT_EQ(components[0].name, "euclidean");
  EXPECT_EQ(components[0].kind, ComponentKind::kThreshold);
  double d = -1.0;
  distance.Evaluate(std::vector<double>{4.0, 6.0, 3.0}, std::span(&d, 1));
  EXPECT_EQ(d, 5.0);  // sqrt(3^2 + 4^2 + 0^2), exact
  distance.Evaluate(std::vector<double>{1.0, 2.0, 3.0}, std::span(&d, 1));
  EXPECT_EQ(d, 0.0);
  distance.Evaluate(std::vector<double>{1.5, 2.0, 2.0}, std::span(&d, 1));
  EXPECT_DOUBLE_EQ(d, std::sqrt(1.25));
}

TEST(EuclideanDistance, BatchGivesTheValuesOfEvaluateAndSkipsFailedRows) {
  const EuclideanDistance distance({0.0, 0.0});
  const std::vector<double> rows = {3.0, 4.0, 1.0, 1.0, 6.0, 8.0, 0.5, 0.0};
  std::vector<double> out(4, -1.0);
  std::vector<std::uint8_t> status(4, 0);
  std::vector<char> reasons(4 * kFailureReasonBytes, '\0');
  BatchFailures failures{std::span(status), std::span(reasons)};
  failures.Fail(1, "simulation failed");
  distance.EvaluateBatch(rows, out, failures);
  // Row 1 failed before the call: left as it was, and still failed for its own reason.
  ExpectNear(out, {5.0, -1.0, 10.0, 0.5}, 0.0, "distances");
  EXPECT_EQ(failures.reason(1), "simulation failed");
  for (std::size_t i : {0u, 2u, 3u}) {
    double one = 0.0;
    distance.Evaluate(std::span(rows).subspan(2 * i, 2), std::span(&one, 1));
    EXPECT_EQ(out[i], one) << "row " << i;
    EXPECT_FALSE(failures.failed(i)) << "row " << i;
  }
}

}  // namespace
}  // namespace combabc
