#include "combabc/config/distance_from_config.hpp"

#include "combabc/core/error.hpp"

namespace combabc {

std::unique_ptr<CompositeDistance> MakeDistance(const CalibrationConfig& config,
                                                const MeasuredData& data) {
  return MakeDistance(config, data.positions, data.displacements);
}

std::unique_ptr<CompositeDistance> MakeDistance(const CalibrationConfig& config,
                                                std::span<const double> data_positions,
                                                std::span<const double> data_values) {
  CompositeDistanceOptions options;
  options.normalise_simulated = config.data.normalise;
  try {
    return std::make_unique<CompositeDistance>(config.metric.components,
                                               data_positions,
                                               data_values,
                                               config.simulator.outputs.coordinates,
                                               options);
  } catch (const Error& e) {
    if (!e.file().empty()) throw;
    std::string message = e.message();
    // A preset's windows are the paper's and cannot be edited: say what can be.
    if (config.metric.preset && e.field().rfind("metric.component[", 0) == 0) {
      message += " (the windows of preset \"" + std::string(ToString(*config.metric.preset)) +
                 "\"; write [[metric.component]] tables to choose others)";
    }
    throw Error(e.kind(), message, config.path, e.line(), e.field());
  }
}

}  // namespace combabc
