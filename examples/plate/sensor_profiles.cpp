// Prints the default sensor's normalised centreline profile |w|/max for a few clamp
// configurations, and the first natural frequencies of each: the paper's qualitative
// observations in numbers (docs/model.md, "Qualitative behaviour").
//   sensor_profiles [width_m foundation_N_per_m3]
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "combabc/plate/sensor_model.hpp"

using combabc::plate::SensorModel;
using combabc::plate::SensorOptions;

namespace {

// Clamp k (1-based) of edge 1 and its facing clamp k + 18 on edge 2, both fixed.
std::vector<std::uint8_t> PairsFixed(const std::vector<int>& pairs) {
  std::vector<std::uint8_t> c(36, 0);
  for (int k : pairs) {
    c[k - 1] = 1;
    c[k - 1 + 18] = 1;
  }
  return c;
}

void Print(const SensorModel& model, const std::string& name, const std::vector<std::uint8_t>& c) {
  std::vector<double> out(model.num_outputs());
  model.Profile(c, out);
  std::printf("%-34s", name.c_str());
  for (int k = 30; k <= 80; k += 2) std::printf(" %4.2f", out[k]);
  const auto modes = model.Modes(c, 3);
  std::printf("  | f1..3 = %.1f %.1f %.1f Hz\n",
              modes.frequencies_hz[0],
              modes.frequencies_hz[1],
              modes.frequencies_hz[2]);
}

}  // namespace

int main(int argc, char** argv) {
  SensorOptions options;
  if (argc > 2) {
    options.width = std::atof(argv[1]);
    options.foundation_stiffness = std::atof(argv[2]);
  }
  const SensorModel model(options);
  std::printf("%-34s", "x (cm)");
  for (int k = 30; k <= 80; k += 2) std::printf(" %4d", k);
  std::printf("\n");
  std::vector<int> all(18);
  for (int k = 0; k < 18; ++k) all[k] = k + 1;
  Print(model, "all free", PairsFixed({}));
  Print(model, "all fixed", PairsFixed(all));
  // Load at 45 cm = the boundary between clamps 9 and 10.
  Print(model, "9,10 free; 6-7,12-13 fixed", PairsFixed({6, 7, 12, 13}));
  Print(model, "free 7-12; rest fixed", PairsFixed({1, 2, 3, 4, 5, 6, 13, 14, 15, 16, 17, 18}));
  Print(model, "only 11 fixed", PairsFixed({11}));
  Print(model, "only 12,13 fixed", PairsFixed({12, 13}));
  Print(model, "16-18 fixed", PairsFixed({16, 17, 18}));
  Print(model, "edge 1 fixed only", [] {
    std::vector<std::uint8_t> c(36, 0);
    for (int k = 0; k < 18; ++k) c[k] = 1;
    return c;
  }());
  return 0;
}
