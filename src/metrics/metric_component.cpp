#include "combabc/metrics/metric_component.hpp"

#include <sstream>

namespace combabc {
namespace {

// The paper states its windows in centimetres along the 90 cm sensor.
constexpr double kCentimetre = 0.01;

MetricComponentConfig Window(MetricType type, double from_cm, double to_cm) {
  MetricComponentConfig c;
  c.type = type;
  c.from = from_cm * kCentimetre;
  c.to = to_cm * kCentimetre;
  return c;
}

}  // namespace

ComponentKind KindOf(MetricType type) {
  return type == MetricType::kRise || type == MetricType::kFall ? ComponentKind::kIndicator
                                                                : ComponentKind::kThreshold;
}

ComponentKind KindOf(const MetricComponentConfig& config) {
  return config.noise.model != NoiseModel::kNone ? ComponentKind::kNegLogLikelihood
                                                 : KindOf(config.type);
}

std::string ComponentName(const MetricComponentConfig& config) {
  if (!config.name.empty()) return config.name;
  std::ostringstream out;
  out << ToString(config.type) << '[' << config.from / kCentimetre << '-' << config.to / kCentimetre
      << "cm]";
  return out.str();
}

std::vector<MetricComponentConfig> PresetComponents(MetricPreset preset) {
  switch (preset) {
    case MetricPreset::kArea:  // Eq. 4, "calculated on the interval 48-80 cm"
      return {Window(MetricType::kArea, 48, 80)};
    case MetricPreset::kLeastSquares:
      // Eq. 5 sums y_{48+i} for i = 0..33, i.e. to 81 cm, but the paper's LDV measured only
      // 48-80 cm (section 4): the window is the measured points, i = 0..32. A window past the
      // data is an error (CompositeDistance), so the paper's 81 would reject the paper's data.
      return {Window(MetricType::kLeastSquares, 48, 80)};
    case MetricPreset::kSplitLeastSquares:  // Eq. 6 windows, then Eq. 7's H1 and H2
      return {Window(MetricType::kLeastSquares, 71, 75),
              Window(MetricType::kLeastSquares, 76, 80),
              Window(MetricType::kLeastSquares, 81, 89),
              Window(MetricType::kRise, 76, 78),
              Window(MetricType::kFall, 78, 80)};
  }
  return {};
}

}  // namespace combabc
