#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal.hpp"

namespace combabc {
namespace {

ContinuousParameter Real(std::string name, ContinuousPrior prior) {
  return {std::move(name), prior};
}

ParameterSpace TwoRealSpace() {
  return ParameterSpace(BinarySpace::Independent(1),
                        {Real("x", {.kind = PriorKind::kUniform, .low = 0.0, .high = 1.0}),
                         Real("y",
                              {.kind = PriorKind::kTruncatedNormal,
                               .low = 0.0,
                               .high = 4.0,
                               .mean = 1.0,
                               .sd = 2.0})});
}

// The base class's Prior only; Fit is not under test here.
class PriorOnlyKernel final : public ContinuousKernel {
 public:
  std::string name() const override { return "prior only"; }
  std::unique_ptr<ContinuousProposal> Fit(const Population&,
                                          const ParameterSpace& space) const override {
    return Prior(space);
  }
};

TEST(ContinuousKernelPrior, DrawsEachRealFromItsPriorInOrder) {
  const ParameterSpace space = TwoRealSpace();
  const auto proposal = PriorOnlyKernel().Prior(space);
  RandomStream rng(1, 2, 3), replay(1, 2, 3);
  std::vector<double> r(2);
  for (int i = 0; i < 1000; ++i) {
    proposal->Sample(rng, r);
    // Same stream, the priors in order: the same numbers.
    EXPECT_EQ(r[0], space.reals()[0].prior.Sample(replay));
    EXPECT_EQ(r[1], space.reals()[1].prior.Sample(replay));
    EXPECT_TRUE(space.InSupport(r));
    EXPECT_DOUBLE_EQ(proposal->LogDensity(r), space.LogPriorReals(r));
  }
  const std::vector<double> outside = {1.5, 1.0};
  EXPECT_EQ(proposal->LogDensity(outside), -INFINITY);
}

}  // namespace
}  // namespace combabc
