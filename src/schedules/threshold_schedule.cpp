#include "combabc/schedules/threshold_schedule.hpp"

#include <algorithm>
#include <cmath>

#include "combabc/core/check.hpp"

namespace combabc {

bool ThresholdSchedule::IsValid(const std::string& where, int num_waves, std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = where + "." + msg;
    return false;
  };
  if (kind == ThresholdKind::kList) {
    if (static_cast<int>(values.size()) != num_waves) {
      return fail("values has " + std::to_string(values.size()) +
                  " entries; must have one per wave (num_waves = " + std::to_string(num_waves) +
                  ")");
    }
    for (std::size_t t = 0; t < values.size(); ++t) {
      if (!(values[t] >= 0.0)) {
        return fail("values[" + std::to_string(t) + "] = " + std::to_string(values[t]) +
                    "; must be >= 0");
      }
      if (t > 0 && values[t] > values[t - 1]) {
        return fail("values[" + std::to_string(t) + "] = " + std::to_string(values[t]) +
                    " > values[" + std::to_string(t - 1) +
                    "]; thresholds must not increase (Eq. 1)");
      }
    }
    return true;
  }
  if (!(quantile > 0.0 && quantile <= 1.0)) {
    return fail("quantile = " + std::to_string(quantile) + "; must be in (0, 1]");
  }
  if (!(initial >= 0.0)) return fail("initial = " + std::to_string(initial) + "; must be >= 0");
  if (!(target >= 0.0 && std::isfinite(target))) {
    return fail("target = " + std::to_string(target) + "; must be finite and >= 0");
  }
  if (target > initial) {
    return fail("target = " + std::to_string(target) + " > initial = " + std::to_string(initial) +
                "; the schedule must decrease");
  }
  return true;
}

double ThresholdSchedule::ThresholdFor(int wave,
                                       std::span<const double> previous_accepted,
                                       std::span<const double> weights) const {
  if (kind == ThresholdKind::kList) return values.at(static_cast<std::size_t>(wave));
  if (wave == 0 || previous_accepted.empty()) return std::max(initial, target);
  return std::max(target,
                  weights.empty() ? EmpiricalQuantile(previous_accepted, quantile)
                                  : WeightedQuantile(previous_accepted, weights, quantile));
}

bool ThresholdSchedule::IsFinal(int wave, double eps) const {
  if (kind == ThresholdKind::kList) return wave + 1 >= static_cast<int>(values.size());
  return eps <= target;
}

double EmpiricalQuantile(std::span<const double> values, double alpha) {
  COMBABC_CHECK(!values.empty() && alpha > 0.0 && alpha <= 1.0);
  std::vector<double> v(values.begin(), values.end());
  // Smallest x with (#values <= x) / n >= alpha: the ceil(alpha n)-th order statistic.
  auto rank = static_cast<std::size_t>(std::ceil(alpha * static_cast<double>(v.size())));
  rank = std::clamp<std::size_t>(rank, 1, v.size());
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(rank - 1), v.end());
  return v[rank - 1];
}

double WeightedQuantile(std::span<const double> values,
                        std::span<const double> weights,
                        double alpha) {
  COMBABC_CHECK(!values.empty() && values.size() == weights.size() && alpha > 0.0 && alpha <= 1.0);
  std::vector<std::size_t> order(values.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  // Ties by index, so that the order (and the cumulative sums) never depend on the sort.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return values[a] < values[b] || (values[a] == values[b] && a < b);
  });
  double total = 0.0;
  for (double w : weights) total += w;
  COMBABC_CHECK(total > 0.0);
  double cumulative = 0.0;
  for (std::size_t i : order) {
    cumulative += weights[i];
    if (cumulative >= alpha * total) return values[i];
  }
  return values[order.back()];
}

}  // namespace combabc
