#pragma once
// The building blocks of the paper's distances between the measured profile Y and a simulated
// profile Y* (Shamas et al. 2024, section 5), each over a window of positions along the sensor:
//   area           Eq. 4: |A(Y) - A(Y*)| / A(Y), A by the trapezoid rule over the window's points
//   least_squares  Eq. 5: sum_j (y*_j - y_j)^2 over the window's points (Eq. 6 = several of them)
//   rise           Eq. 7 H1: 1 if y*(to) - y*(from) > 0, else 0
//   fall           Eq. 7 H2: 1 if y*(to) - y*(from) < 0, else 0
// area and least_squares are threshold components (d_k <= eps_k); rise and fall are indicator
// components that must equal 1. A least_squares component with a noise model is a negative
// log-likelihood instead (docs/algorithm.md, "Noise-aware acceptance"), gaussian:
//   d = sum_j (y*_j - y_j)^2 / (2 sigma^2),  sigma^2 = sigma_noise^2 + sigma_model^2,
// folded_normal (amplitudes y_j = |Y*_j + e_j|): d = sum_j -log(f(y_j; Y*_j) / max_mu f(y_j; mu)),
// accepted with probability exp(-(d - m) / T).
#include <optional>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"

#include "combabc/distances/distance.hpp"
#include "combabc/schedules/threshold_schedule.hpp"

namespace combabc {

enum class MetricType { kArea, kLeastSquares, kRise, kFall };
template <>
struct EnumNames<MetricType> {
  static constexpr std::pair<MetricType, const char*> kNames[] = {
      {MetricType::kArea, "area"},
      {MetricType::kLeastSquares, "least_squares"},
      {MetricType::kRise, "rise"},
      {MetricType::kFall, "fall"},
  };
};
// kThreshold for area / least_squares, kIndicator for rise / fall.
ComponentKind KindOf(MetricType type);

enum class NoiseModel {
  kNone,      // the paper's acceptance: d_k <= eps_k
  kGaussian,  // y_j = Y*_j + e_j, e_j ~ N(0, sigma^2) independent (Wilkinson 2013)
  // y_j = |Y*_j + e_j|, e_j as above: an amplitude (an LDV's, the sensor's maximum displacement)
  // whose noise folds at zero where the signal is small (Leone, Nelson & Nottingham 1961).
  kFoldedNormal,
};
template <>
struct EnumNames<NoiseModel> {
  static constexpr std::pair<NoiseModel, const char*> kNames[] = {
      {NoiseModel::kNone, "none"},
      {NoiseModel::kGaussian, "gaussian"},
      {NoiseModel::kFoldedNormal, "folded_normal"},
  };
};

// The error model of a least_squares component, in the units the metric compares (the
// normalised profile when the data are normalised).
struct NoiseConfig {
  NoiseModel model = NoiseModel::kNone;
  // Measurement noise; nullopt = estimate it from the measured data (EstimateNoiseSigma, or
  // EstimateAmplitudeNoiseSigma for folded_normal).
  std::optional<double> sigma_noise;
  // Model discrepancy, added in quadrature.
  double sigma_model = 0.0;
};

struct MetricComponentConfig {
  MetricType type = MetricType::kLeastSquares;
  // Window [from, to] along the sensor, metres, from < to. area / least_squares use the measured
  // points inside it; rise / fall compare Y* interpolated at exactly `from` and `to`.
  double from = 0.0;
  double to = 0.0;
  // Name reported by Distance::components() and written to the history; empty = generated from
  // the type and window in centimetres, e.g. "least_squares[48-80cm]".
  std::string name;
  // Threshold schedule (threshold components only; ignored for indicators). With a noise model
  // it holds temperatures T >= 1 instead.
  ThresholdSchedule threshold;
  // least_squares only.
  NoiseConfig noise;
  // Line of the config file that defined the component (its [[metric.component]] header or the
  // preset key), for error messages; 0 when not read from a file.
  int config_line = 0;
};

// KindOf(type), except kNegLogLikelihood for a component with a noise model.
ComponentKind KindOf(const MetricComponentConfig& config);

// The name a component reports: config.name, or the generated one.
std::string ComponentName(const MetricComponentConfig& config);

// Shorthands for the paper's three metrics (windows in metres, default threshold schedules).
enum class MetricPreset {
  kArea,               // Eq. 4 on 48-80 cm (Figures 3-4)
  kLeastSquares,       // Eq. 5 on 48-80 cm, the measured points (Figures 5-6)
  kSplitLeastSquares,  // Eq. 6-7: least squares on 71-75, 76-80, 81-89 cm + rise 76-78 (H1)
                       // + fall 78-80 (H2) (Figures 10-11)
};
template <>
struct EnumNames<MetricPreset> {
  static constexpr std::pair<MetricPreset, const char*> kNames[] = {
      {MetricPreset::kArea, "area"},
      {MetricPreset::kLeastSquares, "least_squares"},
      {MetricPreset::kSplitLeastSquares, "split_least_squares"},
  };
};
std::vector<MetricComponentConfig> PresetComponents(MetricPreset preset);

}  // namespace combabc
