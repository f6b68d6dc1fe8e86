// The tiny sensor that the end-to-end, resume and MPI tests calibrate: 3 + 3 clamps on a 2 x 2
// mesh per section, the least-squares metric (Eq. 5) on [0.31, 0.58] m against data.csv in the
// run's folder. Runs of a few hundred simulations take well under a second.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace combabc::testing {

// The config text: `sampler` is the body of the [sampler] table, `tables` anything after it.
inline std::string TinySensorConfig(const std::string& sampler, const std::string& tables = "") {
  return R"([model.clamps]
per_edge = 3

[model.mesh]
elements_per_section = 2
elements_across_width = 2

[data]
csv = "data.csv"
position_column = "position_m"
displacement_column = "displacement_m"
position_unit = "m"
displacement_unit = "m"

[metric]
[[metric.component]]
type = "least_squares"
window = [0.31, 0.58]

[sampler]
)" + sampler +
         "\n" + tables;
}

// The tiny sensors' model choice: clamped (prior 0.4) against simply supported ("pinned", 0.6),
// least squares to the list `thresholds` ("4.0, 3.0, 2.4"); `method` is [model_choice]'s line
// (e.g. "method = \"joint\"\n"), `tables` come before it ([output] ...).
inline std::string TinySensorModelChoice(const std::string& sampler,
                                         const std::string& thresholds,
                                         const std::string& method = "",
                                         const std::string& tables = "") {
  std::string config =
      TinySensorConfig(sampler,
                       tables + "[model_choice]\n" + method +
                           "[[model_choice.model]]\nname = \"clamped\"\n"
                           "prior = 0.4\n[[model_choice.model]]\nname = \"pinned\"\n"
                           "prior = 0.6\nmodel.clamps.fixed_support = "
                           "\"simply_supported\"\n");
  config.replace(config.find("[metric]\n"), 9, "[metric]\nthreshold = [" + thresholds + "]\n");
  return config;
}

// data.csv in `dir`: a tent of height `peak` at 0.45 m, every 3 cm on [0.31, 0.58] m.
inline void WriteTinySensorData(const std::filesystem::path& dir, double peak = 1.0) {
  std::ofstream out(dir / "data.csv");
  out << "position_m,displacement_m\n";
  for (int i = 31; i < 60; i += 3) {
    out << i / 100.0 << "," << peak - std::abs(i / 100.0 - 0.45) << "\n";
  }
}

}  // namespace combabc::testing
