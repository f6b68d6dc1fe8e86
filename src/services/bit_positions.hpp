#pragma once
// Private to src/services: where each bit acts, for the answer's positions, shared by every job
// that summarises or exports a history (history_tools.cpp, report.cpp).
#include <optional>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/history/history_store.hpp"

namespace combabc::services {

// Where each bit acts, from the run's config: the sensor's clamp k (from 1) is section k of edge 1
// (y = 0) for k <= clamps_per_edge, else section k - clamps_per_edge of edge 2, its sections
// splitting the length equally from x = 0 (plate::SensorOptions). Other simulators: none. A
// config this version no longer reads (an older history) has none either: positions only label
// the answer, which stands without them.
inline std::vector<std::optional<BitPosition>> BitPositions(const RunMetadata& metadata) {
  CalibrationConfig config;
  try {
    config = ParseConfig(metadata.config_text, metadata.config_path);
  } catch (const Error&) {
    return {};
  }
  if (config.simulator.kind != SimulatorKind::kSensor) return {};
  const int n = config.model.clamps_per_edge;
  const double length = config.model.length;
  std::vector<std::optional<BitPosition>> positions;
  for (int k = 0; k < 2 * n; ++k) {
    const int section = k % n;
    positions.push_back(
        BitPosition{k < n ? 1 : 2, length * section / n, length * (section + 1) / n});
  }
  return positions;
}

}  // namespace combabc::services
