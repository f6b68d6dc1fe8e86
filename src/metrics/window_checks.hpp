#pragma once
// Checks of a metric component's window against what it is compared on, made once when the
// distance is built (before any simulation): the window must lie within the simulator's output
// positions and within the measured data, and an indicator (Eq. 7) must hold for the measured
// data themselves -- an indicator the data fail rejects the true configuration too.
#include <cstddef>
#include <span>
#include <string>

#include "combabc/metrics/metric_component.hpp"

namespace combabc::metrics_internal {

// Slack (metres) when comparing positions: positions converted from centimetres differ from the
// preset windows by rounding.
inline constexpr double kPositionTolerance = 1e-9;

// "metric.component[i]", the field every per-component error names.
std::string ComponentField(std::size_t index);

// The window in centimetres (the paper's unit, as in ComponentName), e.g. "76-78 cm".
std::string WindowText(double from, double to);

// Throws combabc::Error(kConfig) naming the component and the available range when
// [c.from, c.to] reaches outside [lo, hi]; `what` names the range ("the model's outputs").
void CheckWindowWithin(
    const MetricComponentConfig& c, std::size_t index, double lo, double hi, const char* what);

// For a rise / fall component: throws combabc::Error(kConfig) when the measured profile (linearly
// interpolated at the window's ends, as Y* is) does not rise / fall over the window, saying by how
// much of the data's peak it fails. The window must lie within the data (CheckWindowWithin).
void CheckIndicatorHoldsForData(const MetricComponentConfig& c,
                                std::size_t index,
                                std::span<const double> data_positions,
                                std::span<const double> data_values);

}  // namespace combabc::metrics_internal
