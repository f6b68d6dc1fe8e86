#pragma once
// Private to src/services: what the jobs read back from a history they wrote or export: where
// each bit acts (the answer's positions; history_tools.cpp, report.cpp), and the fit checks with
// the answer at the end of run, resume and enumerate (run.cpp, enumerate.cpp).
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/export/export.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/export/strip.hpp"
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

// The strip's picture (export/strip.hpp) from the run's config: the sensor's plate and clamp
// sections, and each experiment's load and scan line: from its first to its last measured point
// (the history's, in metres; within its data window, when given), or its output positions when the
// history has no points for it.
// None for other simulators, a joint model choice, or a config this version no longer reads.
inline std::optional<StripLayout> StripOf(const RunMetadata& metadata) {
  CalibrationConfig config;
  try {
    config = ParseConfig(metadata.config_text, metadata.config_path);
  } catch (const Error&) {
    return std::nullopt;
  }
  if (config.simulator.kind != SimulatorKind::kSensor) return std::nullopt;
  // A joint model choice's bits are the model indicator and the models' clamps, not one strip's.
  if (config.model_choice) return std::nullopt;
  StripLayout strip;
  strip.length_m = config.model.length;
  strip.width_m = config.model.width;
  strip.clamps_per_edge = config.model.clamps_per_edge;
  const std::vector<ExperimentSlice> slices = ExperimentSlices(metadata);
  const bool sliced = slices.size() == config.experiments.size() && metadata.position_unit == "m";
  for (std::size_t e = 0; e < config.experiments.size(); ++e) {
    const ExperimentConfig& x = config.experiments[e];
    const plate::LoadCase& load = x.load;
    StripExperiment shown;
    shown.name = x.name;
    shown.load_x_m = load.load_x;
    shown.load_y_m = load.load_y_fraction * strip.width_m;
    std::vector<double> scanned = load.output_positions;
    const std::vector<double>& measured = metadata.measured.positions;
    if (sliced && slices[e].measured > 0 &&
        slices[e].first_measured + slices[e].measured <= measured.size()) {
      const auto first = measured.begin() + static_cast<std::ptrdiff_t>(slices[e].first_measured);
      scanned.assign(first, first + static_cast<std::ptrdiff_t>(slices[e].measured));
    }
    if (!scanned.empty()) {
      const auto [low, high] = std::minmax_element(scanned.begin(), scanned.end());
      shown.scan_from_m = *low;
      shown.scan_to_m = *high;
    }
    // The Gaussian extension's points (stored with the measured ones) were not scanned: the data
    // window, when given, bounds the line.
    if (x.data.window_min && x.data.window_max) {
      shown.scan_from_m = std::clamp(shown.scan_from_m, *x.data.window_min, *x.data.window_max);
      shown.scan_to_m = std::clamp(shown.scan_to_m, *x.data.window_min, *x.data.window_max);
    }
    shown.scan_y_m = load.output_y_fraction * strip.width_m;
    strip.experiments.push_back(shown);
  }
  return strip;
}

// The checks' options for a run: the defaults, with the stated noise of its noise-aware
// components from its config (the history records their kind, not their sigma). A config this
// version no longer reads, or whose components do not match the history's, states none: the fit
// is then judged against the data's estimate.
inline FitCheckOptions CheckOptions(const RunMetadata& metadata) {
  FitCheckOptions options;
  CalibrationConfig config;
  try {
    config = ParseConfig(metadata.config_text, metadata.config_path);
  } catch (const Error&) {
    return options;
  }
  std::vector<StatedNoise> stated;
  std::size_t component = 0;
  for (const ExperimentConfig& x : config.experiments) {
    for (const MetricComponentConfig& c : x.metric.components) {
      if (c.noise.model != NoiseModel::kNone) {
        stated.push_back(
            {component, c.noise.sigma_noise, c.noise.sigma_model, c.from, c.to, c.noise.model});
      }
      ++component;
    }
  }
  if (component != metadata.distance_components.size()) return options;
  for (const StatedNoise& s : stated) {
    if (metadata.distance_components[s.component].kind != ComponentKind::kNegLogLikelihood) {
      return options;
    }
  }
  options.stated_noise = std::move(stated);
  return options;
}

// The fit checks and the answer of a finished job's history, from one read of it. Warnings, never
// an error: a history that cannot be read back is for verify to judge; the checks then carry a
// note and the answer is absent.
struct ReadBack {
  FitChecks checks;
  std::optional<Answer> answer;
  std::optional<StripLayout> strip;  // the sensor's: the picture printed with the answer
};
inline ReadBack ReadBackHistory(const HistoryStore& store) {
  ReadBack back;
  try {
    const RunMetadata metadata = store.LoadMetadata();
    const RunHistory history = store.LoadHistory();
    back.checks = ComputeFitChecks(metadata, history, CheckOptions(metadata));
    back.answer = SummariseAnswer(metadata, history, BitPositions(metadata));
    back.strip = StripOf(metadata);
  } catch (const Error& e) {
    back.checks.after.push_back(
        {"note",
         "checks_failed",
         std::string("the fit checks could not read the history: ") + e.what()});
  }
  return back;
}

}  // namespace combabc::services
