#include "combabc/proposals/proposal_options.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

struct Case {
  const char* name;
  std::function<void(ProposalOptions&)> mutate;
  const char* message;
};

TEST(ProposalOptions, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(ProposalOptions{}.IsValid(&why)) << why;
  EXPECT_TRUE(LogisticKernelOptions{}.IsValid(&why)) << why;
}

TEST(ProposalOptions, EachInvalidOptionIsRejectedWithItsMessage) {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::vector<Case> cases = {
      {"correlation high",
       [](ProposalOptions& o) { o.logistic.min_correlation = 1.5; },
       "ProposalOptions::logistic.min_correlation = 1.500000; must be in [0, 1)"},
      {"correlation one",
       [](ProposalOptions& o) { o.logistic.min_correlation = 1.0; },
       "ProposalOptions::logistic.min_correlation = 1.000000; must be in [0, 1)"},
      {"correlation negative",
       [](ProposalOptions& o) { o.logistic.min_correlation = -0.1; },
       "ProposalOptions::logistic.min_correlation = -0.100000; must be in [0, 1)"},
      {"correlation nan",
       [=](ProposalOptions& o) { o.logistic.min_correlation = kNan; },
       "ProposalOptions::logistic.min_correlation = nan; must be in [0, 1)"},
      {"predecessors",
       [](ProposalOptions& o) { o.logistic.max_predecessors = -1; },
       "ProposalOptions::logistic.max_predecessors = -1; must be >= 0"},
      {"ridge zero",
       [](ProposalOptions& o) { o.logistic.ridge = 0.0; },
       "ProposalOptions::logistic.ridge = 0.000000; must be finite and > 0"},
      {"ridge inf",
       [=](ProposalOptions& o) { o.logistic.ridge = kInf; },
       "ProposalOptions::logistic.ridge = inf; must be finite and > 0"},
      {"marginal",
       [](ProposalOptions& o) { o.logistic.min_marginal = 0.5; },
       "ProposalOptions::logistic.min_marginal = 0.500000; must be in [0, 0.5)"},
      {"marginal negative",
       [](ProposalOptions& o) { o.logistic.min_marginal = -0.01; },
       "ProposalOptions::logistic.min_marginal = -0.010000; must be in [0, 0.5)"},
      {"clip zero",
       [](ProposalOptions& o) { o.logistic.clip = 0.0; },
       "ProposalOptions::logistic.clip = 0.000000; must be in (0, 0.5)"},
      {"clip half",
       [](ProposalOptions& o) { o.logistic.clip = 0.5; },
       "ProposalOptions::logistic.clip = 0.500000; must be in (0, 0.5)"},
      {"scale zero",
       [](ProposalOptions& o) { o.scale = 0.0; },
       "ProposalOptions::scale = 0.000000; must be finite and > 0"},
      {"scale nan",
       [=](ProposalOptions& o) { o.scale = kNan; },
       "ProposalOptions::scale = nan; must be finite and > 0"},
      {"scale inf",
       [=](ProposalOptions& o) { o.scale = kInf; },
       "ProposalOptions::scale = inf; must be finite and > 0"},
  };
  for (const auto& c : cases) {
    ProposalOptions o;
    c.mutate(o);
    std::string why;
    EXPECT_FALSE(o.IsValid(&why)) << c.name;
    EXPECT_EQ(why, c.message) << c.name;
    // The parts: the config reads the field from them, and the sentence is theirs.
    ValidationError error;
    EXPECT_FALSE(o.IsValid(&error)) << c.name;
    EXPECT_EQ(error.owner, "ProposalOptions") << c.name;
    EXPECT_EQ(error.Message(), c.message) << c.name;
    EXPECT_FALSE(o.IsValid(static_cast<ValidationError*>(nullptr))) << c.name;
  }
}

TEST(ProposalOptions, LogisticOptionsOnTheirOwnNameTheirStruct) {
  LogisticKernelOptions o;
  o.max_predecessors = -2;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "LogisticKernelOptions::max_predecessors = -2; must be >= 0");
}

TEST(ProposalOptions, BoundaryValuesAreAccepted) {
  ProposalOptions o;
  o.logistic.min_correlation = 0.0;
  o.logistic.max_predecessors = 0;
  o.logistic.min_marginal = 0.0;
  o.logistic.clip = 0.49;
  o.scale = 1e-6;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
}

TEST(ProposalOptions, MakeBinaryKernelBuildsTheLogisticKernel) {
  ProposalOptions o;
  o.binary = BinaryKernelKind::kLogistic;
  EXPECT_EQ(MakeBinaryKernel(o)->name(), "logistic");
  o.logistic.ridge = -1.0;
  EXPECT_THROW(MakeBinaryKernel(o), Error);
}

}  // namespace
}  // namespace combabc
