// The continuation probabilities' optimum (Prescott & Baker 2021, Proposition 10) against a brute
// force search of phi on a fine grid of the box [floor, 1]^2.
#include <gtest/gtest.h>

#include <cmath>

#include "samplers/continuation_tuning.hpp"

namespace combabc {
namespace {

// The grid's best phi: the closed form must be at least as good (up to rounding).
double GridMinimum(const ContinuationStatistics& s, double floor) {
  constexpr int kSteps = 400;
  double best = INFINITY;
  for (int i = 0; i <= kSteps; ++i) {
    for (int j = 0; j <= kSteps; ++j) {
      const double eta_1 = floor + (1.0 - floor) * i / kSteps;
      const double eta_2 = floor + (1.0 - floor) * j / kSteps;
      best = std::min(best, ContinuationObjective(s, eta_1, eta_2));
    }
  }
  return best;
}

TEST(ContinuationTuning, MatchesGridSearch) {
  // Interior optimum, both edges, negative k (many false positives), cheap and dear expensive
  // models, a cheap model that accepts almost everything or almost nothing.
  const ContinuationStatistics cases[] = {
      {1.0, 0.05, 0.02, 0.3, 50.0},
      {1.0, 0.05, 0.02, 0.3, 0.5},
      {1.0, 0.6, 0.3, 0.3, 10.0},
      {1.0, 0.7, 0.5, 0.5, 3.0},
      {1.0, 0.001, 0.4, 0.05, 200.0},
      {1.0, 0.4, 0.001, 0.95, 200.0},
      {2.0, 0.1, 0.1, 0.99, 1e4},
      {2.0, 0.1, 0.1, 0.01, 1e4},
  };
  for (double floor : {0.01, 0.1, 0.5}) {
    for (const auto& s : cases) {
      const auto eta = OptimalContinuation(s, floor);
      ASSERT_GE(eta.continue_if_accepted, floor);
      ASSERT_LE(eta.continue_if_accepted, 1.0);
      ASSERT_GE(eta.continue_if_rejected, floor);
      ASSERT_LE(eta.continue_if_rejected, 1.0);
      const double phi =
          ContinuationObjective(s, eta.continue_if_accepted, eta.continue_if_rejected);
      const double grid = GridMinimum(s, floor);
      EXPECT_LE(phi, grid * (1.0 + 1e-12))
          << "W " << s.w << " fp " << s.w_false_positive << " fn " << s.w_false_negative << " P1 "
          << s.cheap_accepted << " r " << s.cost_ratio << " floor " << floor;
      // And the grid comes close to it (the grid is fine enough to be a real check).
      EXPECT_GE(phi, grid * (1.0 - 1e-3));
    }
  }
}

TEST(ContinuationTuning, InteriorOptimumIsTheClosedForm) {
  // Lemma 8: eta_i = sqrt(W_i / (a_i k)), k = W - W_fp - W_fn, a_1 = r P_1, a_2 = r (1 - P_1).
  const ContinuationStatistics s{1.0, 0.05, 0.02, 0.3, 50.0};
  const auto eta = OptimalContinuation(s, 0.01);
  EXPECT_DOUBLE_EQ(eta.continue_if_accepted, std::sqrt(0.05 / (50.0 * 0.3 * 0.93)));
  EXPECT_DOUBLE_EQ(eta.continue_if_rejected, std::sqrt(0.02 / (50.0 * 0.7 * 0.93)));
}

TEST(ContinuationTuning, NoErrorsOfAKindGoesToTheFloor) {
  // A perfect cheap model: no false positive or negative, so the expensive one only costs.
  const auto perfect = OptimalContinuation({1.0, 0.0, 0.0, 0.2, 10.0}, 0.02);
  EXPECT_EQ(perfect.continue_if_accepted, 0.02);
  EXPECT_EQ(perfect.continue_if_rejected, 0.02);
  // Only false negatives: eta_1 at the floor, eta_2 above it.
  const auto negatives = OptimalContinuation({1.0, 0.0, 0.3, 0.2, 10.0}, 0.02);
  EXPECT_EQ(negatives.continue_if_accepted, 0.02);
  EXPECT_GT(negatives.continue_if_rejected, 0.02);
}

TEST(ContinuationTuning, ErrorsOutweighingTruthContinueAlways) {
  // k <= 0 and a free expensive model: continuing is never worse.
  const auto eta = OptimalContinuation({1.0, 0.8, 0.5, 0.5, 1e-9}, 0.01);
  EXPECT_EQ(eta.continue_if_accepted, 1.0);
  EXPECT_EQ(eta.continue_if_rejected, 1.0);
}

}  // namespace
}  // namespace combabc
