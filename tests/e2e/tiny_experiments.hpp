// Configs with [[experiment]] tables on the tiny sensor (tiny_sensor.hpp: 3 + 3 clamps, a 2 x 2
// mesh per section), and each experiment alone as a single-experiment config (the shorthand
// [model.load], [model.output], [data], [metric]) that must give the same simulation and distance.
#pragma once

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace combabc::testing {

// One experiment: its load and scan, its data file and its metric's window (and threshold
// schedule, the body of `threshold = ...`, empty for the [metric] default).
struct TinyExperiment {
  std::string name;
  double load_x = 0.45;           // m
  double frequency = 5.0;         // Hz
  double from = 0.31, to = 0.58;  // the metric window and the data's extent, m (whole cm)
  std::string output;             // the body of [experiment.output] / [model.output], if any
  std::string threshold;          // e.g. "[1.0, 0.5]"; empty: the [metric] default schedule
  std::string csv() const { return name + ".csv"; }
};

inline TinyExperiment Experiment(std::string name,
                                 double load_x,
                                 double frequency,
                                 double from,
                                 double to,
                                 std::string output = "",
                                 std::string threshold = "") {
  TinyExperiment x;
  x.name = std::move(name);
  x.load_x = load_x;
  x.frequency = frequency;
  x.from = from;
  x.to = to;
  x.output = std::move(output);
  x.threshold = std::move(threshold);
  return x;
}

// Shortest text that reads back as the same double.
inline std::string Exact(double v) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, v).ptr);
}

inline std::string TinyModel() {
  return R"([model.clamps]
per_edge = 3

[model.mesh]
elements_per_section = 2
elements_across_width = 2
)";
}

inline std::string DataBody(const TinyExperiment& x) {
  return "csv = \"" + x.csv() +
         "\"\nposition_column = \"position_m\"\ndisplacement_column = \"displacement_m\"\n"
         "position_unit = \"m\"\ndisplacement_unit = \"m\"\n";
}

inline std::string ComponentBody(const TinyExperiment& x) {
  std::string body =
      "type = \"least_squares\"\nwindow = [" + Exact(x.from) + ", " + Exact(x.to) + "]\n";
  if (!x.threshold.empty()) body += "threshold = " + x.threshold + "\n";
  return body;
}

// The config with one [[experiment]] table per experiment; `sampler` is the body of [sampler],
// `tables` anything after it.
inline std::string ExperimentsConfig(const std::vector<TinyExperiment>& experiments,
                                     const std::string& sampler,
                                     const std::string& tables = "") {
  std::string text = TinyModel();
  for (const TinyExperiment& x : experiments) {
    text += "\n[[experiment]]\nname = \"" + x.name +
            "\"\n[experiment.load]\nx = " + Exact(x.load_x) +
            "\nfrequency = " + Exact(x.frequency) + "\n";
    if (!x.output.empty()) text += "[experiment.output]\n" + x.output;
    text += "[experiment.data]\n" + DataBody(x) + "[experiment.metric]\n" +
            "[[experiment.metric.component]]\n" + ComponentBody(x);
  }
  return text + "\n[sampler]\n" + sampler + "\n" + tables;
}

// One experiment alone, written with the shorthand keys.
inline std::string SingleExperimentConfig(const TinyExperiment& x,
                                          const std::string& sampler,
                                          const std::string& tables = "") {
  std::string text = TinyModel() + "\n[model.load]\nx = " + Exact(x.load_x) +
                     "\nfrequency = " + Exact(x.frequency) + "\n";
  if (!x.output.empty()) text += "\n[model.output]\n" + x.output;
  text += "\n[data]\n" + DataBody(x) + "\n[metric]\n[[metric.component]]\n" + ComponentBody(x);
  return text + "\n[sampler]\n" + sampler + "\n" + tables;
}

// The experiment's data file in `dir`: `value(x)` every 3 cm from `from` to `to` (whole cm, `to -
// from` a multiple of 3 cm, so that the data reach the window's ends exactly).
template <typename Value>
void WriteExperimentData(const std::filesystem::path& dir, const TinyExperiment& x, Value value) {
  std::ofstream out(dir / x.csv());
  out << "position_m,displacement_m\n";
  const int from = static_cast<int>(std::lround(x.from * 100));
  const int to = static_cast<int>(std::lround(x.to * 100));
  for (int cm = from; cm <= to; cm += 3) {
    const double position = cm / 100.0;
    out << Exact(position) << "," << Exact(value(position)) << "\n";
  }
}

// A tent of height 1 at the experiment's load.
inline void WriteTentData(const std::filesystem::path& dir, const TinyExperiment& x) {
  WriteExperimentData(dir, x, [&](double p) { return 1.0 - std::abs(p - x.load_x); });
}

}  // namespace combabc::testing
