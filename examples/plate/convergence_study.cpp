// Mesh convergence of the default sensor's normalised centreline profile (docs/model.md,
// "Convergence study"): for random clamp configurations, the largest difference
// max_x | p_h(x) - p_ref(x) | (p normalised to a maximum of 1, so the error is in units of the
// peak) between a mesh and one `factor_x` / `factor_y` times finer along / across the strip.
//   convergence_study [elements_per_section elements_across_width factor_x factor_y
//                      configurations seed length_grading width_grading theory element_order]
// (theory: "rzt", the default model's, "fsdt" or "kirchhoff"; element_order: the theory's own
// unless given, 2 (9-node quadratic elements) for the shear theories and 1 for Kirchhoff, on both
// meshes; so without arguments: the default model's 10 x 3 quadratic RZT against 40 x 12)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "combabc/plate/sensor_model.hpp"

using combabc::plate::SensorModel;
using combabc::plate::SensorOptions;

int main(int argc, char** argv) {
  const int m = argc > 1 ? std::atoi(argv[1]) : SensorOptions{}.elements_per_section;
  const int ny = argc > 2 ? std::atoi(argv[2]) : SensorOptions{}.ElementsAcrossWidth();
  const int factor_x = argc > 3 ? std::atoi(argv[3]) : 4;
  const int factor_y = argc > 4 ? std::atoi(argv[4]) : 4;
  const int configurations = argc > 5 ? std::atoi(argv[5]) : 200;
  const std::uint64_t seed = argc > 6 ? std::strtoull(argv[6], nullptr, 10) : 7;
  SensorOptions coarse_options;
  if (argc > 7) coarse_options.length_grading = std::atof(argv[7]);
  if (argc > 8) coarse_options.width_grading = std::atof(argv[8]);
  if (argc > 9) {
    const auto theory = combabc::ParseEnum<combabc::plate::PlateTheory>(argv[9]);
    if (!theory) {
      std::fprintf(stderr,
                   "unknown theory %s; expected %s\n",
                   argv[9],
                   combabc::EnumChoices<combabc::plate::PlateTheory>().c_str());
      return 2;
    }
    coarse_options.theory = *theory;
  }
  if (argc > 10) coarse_options.element_order = std::atoi(argv[10]);
  coarse_options.elements_per_section = m;
  coarse_options.elements_across_width = ny;
  SensorOptions fine_options = coarse_options;
  fine_options.elements_per_section = factor_x * m;
  fine_options.elements_across_width = factor_y * ny;
  const auto t0 = std::chrono::steady_clock::now();
  const SensorModel coarse(coarse_options);
  const SensorModel fine(fine_options);
  const auto t1 = std::chrono::steady_clock::now();
  std::mt19937_64 rng(seed);
  std::vector<double> a(coarse.num_outputs());
  std::vector<double> b(fine.num_outputs());
  std::vector<std::uint8_t> clamps(coarse.num_clamps());
  double worst = 0.0;
  double sum = 0.0;
  double worst_window = 0.0;  // the paper's measured window, 48-80 cm
  for (int i = 0; i < configurations; ++i) {
    for (auto& c : clamps) c = static_cast<std::uint8_t>(rng() & 1);
    coarse.Profile(clamps, a);
    fine.Profile(clamps, b);
    double e = 0.0;
    double e_window = 0.0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      const double d = std::abs(a[k] - b[k]);
      e = std::max(e, d);
      const double x = coarse.output_positions()[k];
      if (x >= 0.48 - 1e-9 && x <= 0.80 + 1e-9) e_window = std::max(e_window, d);
    }
    worst = std::max(worst, e);
    worst_window = std::max(worst_window, e_window);
    sum += e;
  }
  const auto t2 = std::chrono::steady_clock::now();
  std::printf(
      "grading %.1f/%.1f, order %d, mesh %d x %d per section (h_x = %.2f mm, h_y = %.2f mm) vs "
      "%dx%d finer, "
      "%d configurations: "
      "worst %.4f, mean %.4f, worst in 48-80 cm %.4f (precompute %.1f s, solves %.1f s)\n",
      coarse_options.length_grading,
      coarse_options.WidthGrading(),
      coarse_options.ElementOrder(),
      m,
      ny,
      1e3 * coarse_options.length / (18.0 * m),
      1e3 * coarse_options.width / ny,
      factor_x,
      factor_y,
      configurations,
      worst,
      sum / configurations,
      worst_window,
      std::chrono::duration<double>(t1 - t0).count(),
      std::chrono::duration<double>(t2 - t1).count());
  return 0;
}
