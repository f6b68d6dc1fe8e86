#pragma once
// Builds the run's distance from a parsed config and its loaded data: the metric's components,
// compared on the data positions against Y* at the model's output positions, normalised as the
// data are (paper section 5).
#include <memory>
#include <span>

#include "combabc/config/config.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/metrics/composite_distance.hpp"

namespace combabc {

// Throws combabc::Error(kConfig) as CompositeDistance does, with the config file's path attached:
// a metric window reaching past the model's output positions or the data, or a rise / fall
// indicator (Eq. 7) that the measured data themselves fail. Nothing has been simulated yet.
std::unique_ptr<CompositeDistance> MakeDistance(const CalibrationConfig& config,
                                                const MeasuredData& data);

// Same, from the data's positions (metres) and values as the run uses them (e.g. as a resumed
// run's history recorded them).
std::unique_ptr<CompositeDistance> MakeDistance(const CalibrationConfig& config,
                                                std::span<const double> data_positions,
                                                std::span<const double> data_values);

}  // namespace combabc
