#include "combabc/schedules/threshold_schedule.hpp"

#include <algorithm>
#include <cmath>

#include "combabc/core/check.hpp"

namespace combabc {

bool ThresholdSchedule::IsValid(const std::string& where, int num_waves, std::string* why) const {
  ValidationError error;
  const bool valid = IsValid(num_waves, &error);
  error.field = where + "." + error.field;
  return ExplainValidation(valid, error, why);
}

bool ThresholdSchedule::IsValid(int num_waves, ValidationError* error) const {
  // fail(field, value, constraint); with no value, constraint is what follows the field.
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rest) {
    if (error) *error = {"", field, value, rest};
    return false;
  };
  if (kind == ThresholdKind::kList) {
    if (static_cast<int>(values.size()) != num_waves) {
      return fail("values",
                  "",
                  "has " + std::to_string(values.size()) +
                      " entries; must have one per wave (num_waves = " + std::to_string(num_waves) +
                      ")");
    }
    for (std::size_t t = 0; t < values.size(); ++t) {
      const std::string field = "values[" + std::to_string(t) + "]";
      if (!(values[t] >= 0.0)) return fail(field, std::to_string(values[t]), "must be >= 0");
      if (t > 0 && values[t] > values[t - 1]) {
        return fail(field,
                    std::to_string(values[t]) + " > values[" + std::to_string(t - 1) + "]",
                    "thresholds must not increase (Eq. 1)");
      }
    }
    return true;
  }
  if (kind == ThresholdKind::kQuantile && !(quantile > 0.0 && quantile <= 1.0)) {
    return fail("quantile", std::to_string(quantile), "must be in (0, 1]");
  }
  if (kind != ThresholdKind::kQuantile && weighted) {
    return fail("weighted", "true", "only the quantile schedule takes importance weights");
  }
  if (kind == ThresholdKind::kAcceptance && !(acceptance_rate > 0.0 && acceptance_rate <= 1.0)) {
    return fail("acceptance_rate", std::to_string(acceptance_rate), "must be in (0, 1]");
  }
  if (kind == ThresholdKind::kEss && !(ess_fraction > 0.0 && ess_fraction < 1.0)) {
    return fail("ess_fraction", std::to_string(ess_fraction), "must be in (0, 1)");
  }
  if (!(initial >= 0.0)) return fail("initial", std::to_string(initial), "must be >= 0");
  if (!(target >= 0.0 && std::isfinite(target))) {
    return fail("target", std::to_string(target), "must be finite and >= 0");
  }
  if (target > initial) {
    return fail("target",
                std::to_string(target) + " > initial = " + std::to_string(initial),
                "the schedule must decrease");
  }
  return true;
}

double ThresholdSchedule::ThresholdFor(int wave, const PreviousWave& previous) const {
  if (kind == ThresholdKind::kList) return values.at(static_cast<std::size_t>(wave));
  const std::span<const double> d = previous.distances;
  if (wave == 0 || d.empty()) return std::max(initial, target);
  COMBABC_CHECK(previous.counts.empty() || previous.counts.size() == d.size());
  COMBABC_CHECK(previous.importance.empty() || previous.importance.size() == d.size());
  // counts x importance, or either alone.
  auto weights = [&](bool importance) {
    std::vector<double> w(d.size(), 1.0);
    for (std::size_t i = 0; i < d.size(); ++i) {
      if (!previous.counts.empty()) w[i] *= previous.counts[i];
      if (importance && !previous.importance.empty()) w[i] *= previous.importance[i];
    }
    return w;
  };
  auto quantile_of = [&](double alpha, bool importance) {
    if (previous.counts.empty() && (!importance || previous.importance.empty())) {
      return EmpiricalQuantile(d, alpha);
    }
    return WeightedQuantile(d, weights(importance), alpha);
  };
  double eps = 0.0;
  switch (kind) {
    case ThresholdKind::kQuantile:
      eps = quantile_of(quantile, weighted);
      break;
    case ThresholdKind::kAcceptance: {
      // The accepted distances are the proposal's draws within eps_{t-1}: a fraction F(eps) of
      // them within eps predicts an acceptance rate r_{t-1} F(eps) for eps <= eps_{t-1}, were the
      // next proposal the same. F(eps) = a* / r_{t-1}; at or below the target rate already, the
      // largest accepted distance (no tighter).
      const double rate = previous.acceptance_rate;
      const double alpha = rate > 0.0 ? std::min(1.0, acceptance_rate / rate) : 1.0;
      eps = quantile_of(alpha, false);
      break;
    }
    case ThresholdKind::kEss:
      eps = EssThreshold(d, weights(true), ess_fraction);
      break;
    case ThresholdKind::kList:
      break;
  }
  return std::max(target, eps);
}

double EssThreshold(std::span<const double> values, std::span<const double> weights, double alpha) {
  COMBABC_CHECK(!values.empty() && values.size() == weights.size() && alpha > 0.0 && alpha <= 1.0);
  std::vector<std::size_t> order(values.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return values[a] < values[b] || (values[a] == values[b] && a < b);
  });
  double s1 = 0.0, s2 = 0.0;
  for (const double w : weights) {
    s1 += w;
    s2 += w * w;
  }
  COMBABC_CHECK(s1 > 0.0);
  const double wanted = alpha * s1 * s1 / s2;
  double c1 = 0.0, c2 = 0.0;
  for (std::size_t r = 0; r < order.size(); ++r) {
    const std::size_t i = order[r];
    c1 += weights[i];
    c2 += weights[i] * weights[i];
    // Ties enter together: a threshold keeps every particle at its value.
    const bool last_of_value = r + 1 == order.size() || values[order[r + 1]] != values[i];
    if (last_of_value && c2 > 0.0 && c1 * c1 >= wanted * c2) return values[i];
  }
  return values[order.back()];
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
