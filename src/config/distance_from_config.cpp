#include "combabc/config/distance_from_config.hpp"

#include "combabc/core/error.hpp"

namespace combabc {

std::unique_ptr<CompositeDistance> MakeDistance(const CalibrationConfig& config,
                                                const MeasuredData& data) {
  CompositeDistanceOptions options;
  options.normalise_simulated = config.data.normalise;
  try {
    return std::make_unique<CompositeDistance>(config.metric.components,
                                               data.positions,
                                               data.displacements,
                                               config.model.output_positions,
                                               options);
  } catch (const Error& e) {
    if (!e.file().empty()) throw;
    throw Error(e.kind(), e.message(), config.path, e.line(), e.field());
  }
}

}  // namespace combabc
