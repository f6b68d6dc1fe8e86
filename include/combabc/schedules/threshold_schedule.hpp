#pragma once
// Threshold schedules for one distance component (paper Eq. 1): an explicit decreasing list, or
// adaptive — the alpha-quantile of the previous wave's accepted distances, floored at a target.
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"

namespace combabc {

enum class ThresholdKind {
  kList,      // eps_t = values[t]; the last value is the target
  kQuantile,  // eps_0 = initial; eps_t = max(target, alpha-quantile of wave t-1's distances)
};
template <>
struct EnumNames<ThresholdKind> {
  static constexpr std::pair<ThresholdKind, const char*> kNames[] = {
      {ThresholdKind::kList, "list"},
      {ThresholdKind::kQuantile, "quantile"},
  };
};

struct ThresholdSchedule {
  ThresholdKind kind = ThresholdKind::kQuantile;
  std::vector<double> values;  // kList: one per wave, non-increasing, >= 0
  double quantile = 0.5;       // kQuantile: alpha in (0, 1]
  double initial = std::numeric_limits<double>::infinity();  // kQuantile: eps_0 (inf = prior)
  double target = 0.0;  // kQuantile: the run stops once eps reaches it

  // `where` prefixes messages, e.g. "SmcOptions::thresholds[1]".
  bool IsValid(const std::string& where, int num_waves, std::string* why) const;

  // Threshold for wave t given the previous wave's accepted distances for this component
  // (empty for t = 0), weighted by `weights` when given (one per distance, >= 0; a
  // multi-fidelity run's confirmed particles counted 1 / their continuation probability).
  double ThresholdFor(int wave,
                      std::span<const double> previous_accepted,
                      std::span<const double> weights = {}) const;
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

}  // namespace combabc
