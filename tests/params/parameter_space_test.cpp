#include "combabc/params/parameter_space.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

ContinuousParameter Real(std::string name, ContinuousPrior prior) {
  return {std::move(name), prior};
}
ContinuousPrior Uniform(double low, double high) {
  return {.kind = PriorKind::kUniform, .low = low, .high = high};
}
ContinuousPrior Normal(double mean, double sd) {
  return {.kind = PriorKind::kNormal, .mean = mean, .sd = sd};
}

// The ctor's error for `reals`, or "" if it does not throw.
Error ConstructionError(std::vector<ContinuousParameter> reals) {
  try {
    ParameterSpace space(BinarySpace::Independent(2), std::move(reals));
  } catch (const Error& e) {
    return e;
  }
  return Error(ErrorKind::kUsage, "no error");
}

TEST(ParameterSpace, RejectsAnInvalidPriorNamingTheParameterAndField) {
  const Error e =
      ConstructionError({Real("stiffness", Uniform(0.0, 1.0)), Real("damping", Normal(0.0, -1.0))});
  EXPECT_EQ(e.kind(), ErrorKind::kConfig);
  EXPECT_EQ(e.field(), "reals[1] (damping)");
  EXPECT_NE(e.message().find("sd = -1; must be > 0"), std::string::npos) << e.message();
  EXPECT_NE(e.message().find("normal prior"), std::string::npos) << e.message();
}

TEST(ParameterSpace, RejectsEmptyDuplicateAndBitClashingNames) {
  Error e = ConstructionError({Real("", Uniform(0.0, 1.0))});
  EXPECT_EQ(e.kind(), ErrorKind::kConfig);
  EXPECT_EQ(e.field(), "reals[0] ()");
  EXPECT_NE(e.message().find("empty"), std::string::npos) << e.message();

  e = ConstructionError(
      {Real("a", Uniform(0.0, 1.0)), Real("b", Uniform(0.0, 1.0)), Real("a", Normal(0.0, 1.0))});
  EXPECT_EQ(e.kind(), ErrorKind::kConfig);
  EXPECT_EQ(e.field(), "reals[2] (a)");
  EXPECT_NE(e.message().find("unique"), std::string::npos) << e.message();

  e = ConstructionError({Real(BinarySpace::Independent(2).name(1), Uniform(0.0, 1.0))});
  EXPECT_EQ(e.kind(), ErrorKind::kConfig);
  EXPECT_NE(e.message().find("bit's name"), std::string::npos) << e.message();
}

TEST(ParameterSpace, ContinuousOnlyNeedsAReal) {
  const ParameterSpace space(BinarySpace::Independent(0), {Real("theta", Normal(0.0, 1.0))});
  EXPECT_EQ(space.num_bits(), 0);
  EXPECT_EQ(space.num_reals(), 1);
  EXPECT_DOUBLE_EQ(space.LogPriorBits({}), 0.0);
  try {
    const ParameterSpace empty(BinarySpace::Independent(0));
    ADD_FAILURE() << "a space without parameters was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no parameters"), std::string::npos) << e.what();
  }
}

TEST(ParameterSpace, LogPriorBitsSumsTheFreeBitsPriors) {
  BinarySpaceOptions options;
  options.dimension = 3;
  options.prior_one = {0.2, 0.7, 0.9};
  const ParameterSpace space{BinarySpace(options)};
  EXPECT_EQ(space.num_bits(), 3);
  EXPECT_EQ(space.num_free_bits(), 3);
  EXPECT_EQ(space.num_reals(), 0);
  constexpr double kTol = 1e-14;
  const std::vector<std::uint8_t> bits = {1, 0, 1};
  EXPECT_NEAR(space.LogPriorBits(bits), std::log(0.2) + std::log(0.3) + std::log(0.9), kTol);
  const std::vector<std::uint8_t> zeros = {0, 0, 0};
  EXPECT_NEAR(space.LogPriorBits(zeros), std::log(0.8) + std::log(0.3) + std::log(0.1), kTol);

  // A tie conditions the prior: bits 0 and 2 tied with priors 0.2 and 0.9 give
  // P(free = 1) = 0.18 / (0.18 + 0.08).
  options.tied = {{0, 2}};
  const ParameterSpace tied{BinarySpace(options)};
  ASSERT_EQ(tied.num_free_bits(), 2);
  const std::vector<std::uint8_t> free = {1, 1};
  EXPECT_NEAR(tied.LogPriorBits(free), std::log(0.18 / 0.26) + std::log(0.7), kTol);
  // A bit with prior 1 set to 0 has probability 0.
  options.tied.clear();
  options.prior_one = {1.0, 0.5, 0.5};
  EXPECT_EQ(ParameterSpace(BinarySpace(options)).LogPriorBits(zeros), -INFINITY);
}

TEST(ParameterSpace, LogPriorRealsAndSupport) {
  const ParameterSpace space(BinarySpace::Independent(1),
                             {Real("x", Uniform(0.0, 2.0)), Real("y", Normal(1.0, 3.0))});
  ASSERT_EQ(space.num_reals(), 2);
  EXPECT_EQ(space.reals()[1].name, "y");
  const std::vector<double> inside = {0.5, 4.0};
  EXPECT_NEAR(space.LogPriorReals(inside),
              -std::log(2.0) - 0.5 - std::log(3.0) - 0.5 * std::log(2.0 * M_PI),
              1e-13);
  EXPECT_TRUE(space.InSupport(inside));
  const std::vector<double> outside = {2.5, 4.0};
  EXPECT_FALSE(space.InSupport(outside));
  EXPECT_EQ(space.LogPriorReals(outside), -INFINITY);
}

}  // namespace
}  // namespace combabc
