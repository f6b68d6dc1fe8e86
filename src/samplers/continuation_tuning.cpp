#include "samplers/continuation_tuning.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace combabc {
namespace {

// Eq. 13's factors, with costs in units of a cheap simulation: the variance term is
// k + b_1 / eta_1 + b_2 / eta_2 and the cost term 1 + a_1 eta_1 + a_2 eta_2.
struct Phi {
  double k, b_1, b_2, a_1, a_2;

  explicit Phi(const ContinuationStatistics& s)
      : k(s.w - s.w_false_positive - s.w_false_negative),
        b_1(s.w_false_positive),
        b_2(s.w_false_negative),
        a_1(s.cost_ratio * s.cheap_accepted),
        a_2(s.cost_ratio * (1.0 - s.cheap_accepted)) {}

  double operator()(double eta_1, double eta_2) const {
    return (k + b_1 / eta_1 + b_2 / eta_2) * (1.0 + a_1 * eta_1 + a_2 * eta_2);
  }
};

// The best eta_i in [floor, 1] with the other eta held at x (Lemma 9's eta_1(x), eta_2(x)):
// phi = (v + b / eta)(c + a eta) with v = k + b_other / x and c = 1 + a_other x is minimal at
// sqrt(b c / (a v)); with v <= 0 or a = 0 it only falls as eta grows.
double BestGiven(double b, double a, double v, double c, double floor) {
  if (!(a > 0.0) || !(v > 0.0)) return 1.0;
  return std::clamp(std::sqrt(b * c / (a * v)), floor, 1.0);
}

}  // namespace

double ContinuationObjective(const ContinuationStatistics& s, double eta_1, double eta_2) {
  return Phi(s)(eta_1, eta_2);
}

ContinuationProbabilities OptimalContinuation(const ContinuationStatistics& s, double floor) {
  const Phi phi(s);
  // Lemma 8: with k > 0 the unconstrained minimiser is eta_i = sqrt(b_i / (a_i k)).
  if (phi.k > 0.0 && phi.a_1 > 0.0 && phi.a_2 > 0.0) {
    const double eta_1 = std::sqrt(phi.b_1 / (phi.a_1 * phi.k));
    const double eta_2 = std::sqrt(phi.b_2 / (phi.a_2 * phi.k));
    if (eta_1 >= floor && eta_1 <= 1.0 && eta_2 >= floor && eta_2 <= 1.0) return {eta_1, eta_2};
  }
  // Lemma 9: otherwise the minimum is on an edge of the box, where it is the other eta's best.
  auto eta_1 = [&](double x) {
    return BestGiven(phi.b_1, phi.a_1, phi.k + phi.b_2 / x, 1.0 + phi.a_2 * x, floor);
  };
  auto eta_2 = [&](double x) {
    return BestGiven(phi.b_2, phi.a_2, phi.k + phi.b_1 / x, 1.0 + phi.a_1 * x, floor);
  };
  const std::array<ContinuationProbabilities, 4> edges = {
      {{1.0, eta_2(1.0)}, {eta_1(1.0), 1.0}, {floor, eta_2(floor)}, {eta_1(floor), floor}}};
  // The first of equal minima, so that the choice is deterministic.
  ContinuationProbabilities best = edges[0];
  double best_phi = phi(best.continue_if_accepted, best.continue_if_rejected);
  for (const auto& e : edges) {
    const double value = phi(e.continue_if_accepted, e.continue_if_rejected);
    if (value < best_phi) {
      best = e;
      best_phi = value;
    }
  }
  return best;
}

}  // namespace combabc
