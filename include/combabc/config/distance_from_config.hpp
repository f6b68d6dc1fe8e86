#pragma once
// Builds the run's distance from a parsed config and its loaded data: the metric's components,
// compared on the data positions against Y* at the model's output positions, normalised as the
// data are (paper section 5).
#include <memory>

#include "combabc/config/config.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/metrics/composite_distance.hpp"

namespace combabc {

// Throws combabc::Error(kConfig) as CompositeDistance does (e.g. a metric window reaching past
// the model's output positions), with the config file's path attached.
std::unique_ptr<CompositeDistance> MakeDistance(const CalibrationConfig& config,
                                                const MeasuredData& data);

}  // namespace combabc
