#include "combabc/config/distance_from_config.hpp"

#include "combabc/core/error.hpp"

namespace combabc {

std::vector<MeasuredData> LoadExperimentData(const CalibrationConfig& config) {
  std::vector<MeasuredData> data;
  data.reserve(config.experiments.size());
  for (const ExperimentConfig& x : config.experiments) {
    data.push_back(LoadMeasuredData(x.data, config.directory));
  }
  return data;
}

std::vector<MeasuredProfile> ProfilesOf(const std::vector<MeasuredData>& data) {
  std::vector<MeasuredProfile> profiles;
  profiles.reserve(data.size());
  for (const MeasuredData& d : data) profiles.push_back({d.positions, d.displacements});
  return profiles;
}

std::unique_ptr<JointDistance> MakeDistance(const CalibrationConfig& config,
                                            std::span<const MeasuredProfile> profiles) {
  if (profiles.size() != config.experiments.size()) {
    throw Error(ErrorKind::kSoftware,
                "MakeDistance: " + std::to_string(profiles.size()) + " profiles for " +
                    std::to_string(config.experiments.size()) + " experiments");
  }
  std::vector<JointDistance::Part> parts;
  std::size_t offset = 0;
  for (std::size_t e = 0; e < config.experiments.size(); ++e) {
    const ExperimentConfig& x = config.experiments[e];
    CompositeDistanceOptions options;
    options.normalise_simulated = x.data.normalise;
    JointDistance::Part part;
    part.name = x.name;
    part.output_offset = offset;
    try {
      part.distance = std::make_unique<CompositeDistance>(x.metric.components,
                                                          profiles[e].positions,
                                                          profiles[e].values,
                                                          x.output_coordinates,
                                                          options);
    } catch (const Error& error) {
      if (!error.file().empty()) throw;
      std::string message = error.message();
      // A preset's windows are the paper's and cannot be edited: say what can be.
      if (x.metric.preset && error.field().rfind("metric.component[", 0) == 0) {
        message += " (the windows of preset \"" + std::string(ToString(*x.metric.preset)) +
                   "\"; write [[" + std::string(x.line == 0 ? "metric" : "experiment.metric") +
                   ".component]] tables to choose others)";
      }
      const std::string field =
          x.line == 0 || error.field().empty() ? error.field() : x.Key(e, "") + "." + error.field();
      throw Error(error.kind(), message, config.path, error.line(), field);
    }
    offset += part.distance->output_size();
    parts.push_back(std::move(part));
  }
  return std::make_unique<JointDistance>(std::move(parts));
}

}  // namespace combabc
