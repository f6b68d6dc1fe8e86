#pragma once
// Builds the run's distance from a parsed config and its loaded data: each experiment's metric
// components, compared on its data positions against Y* at its output positions, normalised as
// the data are (paper section 5), joined into one distance vector (JointDistance).
#include <memory>
#include <span>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/metrics/joint_distance.hpp"

namespace combabc {

// One experiment's measured profile as the metric compares it: positions in metres, values
// normalised when its data are.
struct MeasuredProfile {
  std::vector<double> positions;
  std::vector<double> values;
};

// Reads every experiment's data file (LoadMeasuredData), in experiment order.
std::vector<MeasuredData> LoadExperimentData(const CalibrationConfig& config);
std::vector<MeasuredProfile> ProfilesOf(const std::vector<MeasuredData>& data);

// Throws combabc::Error(kConfig) as CompositeDistance does, with the config file's path attached
// and the experiment's key ("experiment[1].metric.component[0]"): a metric window reaching past
// the experiment's output positions or its data, or a rise / fall indicator (Eq. 7) that the
// measured data themselves fail. Nothing has been simulated yet. profiles: one per experiment.
std::unique_ptr<JointDistance> MakeDistance(const CalibrationConfig& config,
                                            std::span<const MeasuredProfile> profiles);

}  // namespace combabc
