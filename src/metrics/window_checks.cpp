#include "metrics/window_checks.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "combabc/core/error.hpp"

namespace combabc::metrics_internal {
namespace {

constexpr double kCentimetre = 0.01;

// y(x) by linear interpolation between the measured points, x within [positions.front(), back()].
double DataAt(std::span<const double> positions, std::span<const double> values, double x) {
  const auto upper = std::upper_bound(positions.begin(), positions.end(), x);
  if (upper == positions.begin()) return values.front();
  if (upper == positions.end()) return values.back();
  const auto i = static_cast<std::size_t>(upper - positions.begin()) - 1;
  const double w = (x - positions[i]) / (positions[i + 1] - positions[i]);
  return (1.0 - w) * values[i] + w * values[i + 1];
}

}  // namespace

std::string ComponentField(std::size_t index) {
  return "metric.component[" + std::to_string(index) + "]";
}

std::string WindowText(double from, double to) {
  std::ostringstream out;
  out << from / kCentimetre << '-' << to / kCentimetre << " cm";
  return out.str();
}

void CheckWindowWithin(
    const MetricComponentConfig& c, std::size_t index, double lo, double hi, const char* what) {
  if (c.from >= lo - kPositionTolerance && c.to <= hi + kPositionTolerance) return;
  throw Error(
      ErrorKind::kConfig,
      "window " + WindowText(c.from, c.to) + " reaches beyond " + what + ", " + WindowText(lo, hi),
      {},
      c.config_line,
      ComponentField(index));
}

void CheckIndicatorHoldsForData(const MetricComponentConfig& c,
                                std::size_t index,
                                std::span<const double> data_positions,
                                std::span<const double> data_values) {
  const bool rise = c.type == MetricType::kRise;
  // Eq. 7: H1 needs y(to) - y(from) > 0, H2 needs it < 0. Evaluated on Y itself, it is what the
  // truth's simulation would give without model error or noise.
  const double change =
      DataAt(data_positions, data_values, c.to) - DataAt(data_positions, data_values, c.from);
  if (rise ? change > 0.0 : change < 0.0) return;
  double peak = 0.0;
  for (double y : data_values) peak = std::max(peak, std::abs(y));
  std::ostringstream how;
  if (change == 0.0 || peak == 0.0) {
    how << "are flat";
  } else {
    how.precision(2);
    how << (change > 0.0 ? "rise" : "fall") << " by " << 100.0 * std::abs(change) / peak
        << " % of their peak";
  }
  throw Error(ErrorKind::kConfig,
              std::string(ToString(c.type)) + " " + WindowText(c.from, c.to) + " (Eq. 7 " +
                  (rise ? "H1" : "H2") + "): the measured data " + how.str() +
                  " over this window, so the indicator would reject the truth; choose a window "
                  "over which the data " +
                  (rise ? "rise" : "fall"),
              {},
              c.config_line,
              ComponentField(index));
}

}  // namespace combabc::metrics_internal
