#pragma once
// Threshold schedules for one distance component (paper Eq. 1): an explicit decreasing list, or
// adaptive, floored at a target — the alpha-quantile of the previous wave's accepted distances
// (optionally weighted by their importance weights), the threshold that predicts a target
// acceptance rate, or the one that keeps a fraction of the previous wave's ESS (Del Moral, Doucet
// & Jasra 2012). docs/algorithm.md, "Threshold schedules".
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"
#include "combabc/core/validation_error.hpp"

namespace combabc {

enum class ThresholdKind {
  kList,        // eps_t = values[t]; the last value is the target
  kQuantile,    // eps_0 = initial; eps_t = max(target, alpha-quantile of wave t-1's distances)
  kAcceptance,  // eps_0 = initial; eps_t = max(target, the eps whose predicted rate is a*)
  kEss,         // eps_0 = initial; eps_t = max(target, the eps that keeps alpha of the ESS)
};
template <>
struct EnumNames<ThresholdKind> {
  static constexpr std::pair<ThresholdKind, const char*> kNames[] = {
      {ThresholdKind::kList, "list"},
      {ThresholdKind::kQuantile, "quantile"},
      {ThresholdKind::kAcceptance, "acceptance"},
      {ThresholdKind::kEss, "ess"},
  };
};

// What an adaptive schedule knows of the previous wave, for one distance component.
struct PreviousWave {
  // The accepted particles' distances for this component.
  std::span<const double> distances = {};
  // How many candidates each stands for (a multi-fidelity run's confirmed particles: 1 / their
  // continuation probability); empty = 1 each.
  std::span<const double> counts = {};
  // Their importance weights (>= 0), as the wave stores them; empty = equal.
  std::span<const double> importance = {};
  // Its acceptance rate, accepted / candidates simulated.
  double acceptance_rate = 1.0;
};

struct ThresholdSchedule {
  ThresholdKind kind = ThresholdKind::kQuantile;
  std::vector<double> values;  // kList: one per wave, non-increasing, >= 0
  double quantile = 0.5;       // kQuantile: alpha in (0, 1]
  // kQuantile: the quantile of the distances weighted by the particles' importance weights (x
  // counts), the posterior's quantile rather than the proposal's.
  bool weighted = false;
  double acceptance_rate = 0.1;  // kAcceptance: the target rate a* in (0, 1]
  double ess_fraction = 0.5;     // kEss: alpha in (0, 1)
  // Adaptive kinds: eps_0 (inf = prior) and the target, where the run stops once eps reaches it.
  double initial = std::numeric_limits<double>::infinity();
  double target = 0.0;

  // On failure `error` names the field ("values[2]", "quantile"), with no owner: the caller knows
  // which schedule it checked.
  bool IsValid(int num_waves, ValidationError* error) const;
  // The same as one sentence that `where` prefixes, e.g. "SmcOptions::thresholds[1]".
  bool IsValid(const std::string& where, int num_waves, std::string* why) const;

  // Threshold for wave t given what the previous wave left (nothing for t = 0).
  double ThresholdFor(int wave, const PreviousWave& previous = {}) const;
  // True when eps is this schedule's last (target) threshold at this wave.
  bool IsFinal(int wave, double eps) const;
};

// The alpha-quantile (inverse empirical CDF, no interpolation: the smallest x with F(x) >= alpha)
// so that at least a fraction alpha of the values lie at or below it. Copies and partially sorts.
double EmpiricalQuantile(std::span<const double> values, double alpha);
// The same under weights w_i >= 0 (sum > 0): the smallest x whose values at or below it carry at
// least a fraction alpha of the total weight.
double WeightedQuantile(std::span<const double> values,
                        std::span<const double> weights,
                        double alpha);
// The smallest of `values` whose particles at or below it keep an effective sample size
// (sum w)^2 / sum w^2 of at least alpha times all the particles' (weights w_i >= 0, sum > 0).
double EssThreshold(std::span<const double> values, std::span<const double> weights, double alpha);

}  // namespace combabc
