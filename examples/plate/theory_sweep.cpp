// When the plate theory matters (docs/model.md, "When the theory matters"): three sweeps, one
// variable at a time from the default sensor of the 45 cm example (load 0.042 N), of the peak
// |w| of Kirchhoff, FSDT and RZT and the shape of their normalised profiles:
//   core_modulus  E_core / E_face from 1 to 1/100 (faces stay 30 MPa; default 1/6), clamps at the
//                 load fixed (sections 9 and 10 of both edges);
//   thickness     total thickness 1 to 8 mm, all three layers scaled alike (default 4 mm), the
//                 same clamps;
//   free_span     the free length between fixed clamps along the strip (cm), a window of free
//                 sections centred on the load with every other section of both edges fixed:
//                 0 = all fixed (the shortest span is then the 4 cm width), 90 = all free.
// The shortest distance between supports sets the shortest wavelength, so these are the three
// ratios that decide how much transverse shear (FSDT) and the core's zigzag (RZT) matter:
// stiffness of the core against the faces, thickness against span, span itself.
// Writes CSV to stdout (progress to stderr); scripts/figures/theories.py plots it.
// Usage: plate_theory_sweep [mesh refinement factor, default 1: 10 x 6 per section]
// At the default mesh FSDT's and RZT's peaks next to fixed clamps are about 8 % below converged
// (docs/model.md, "Mesh convergence of the shear theories"); factor 2 takes about 7 times longer
// (examples/plate/README.md).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "combabc/plate/sensor_model.hpp"
#include "profile_metrics.hpp"

using combabc::plate::Layer;
using combabc::plate::PlateTheory;
using combabc::plate::SensorModel;
using combabc::plate::SensorOptions;
using plate_examples::BothEdges;
using plate_examples::Magnitudes;
using plate_examples::Peak;
using plate_examples::ProfileDifference;

namespace {

struct Point {
  std::string sweep;
  double value;  // the sweep's variable, in the units the CSV header names
  SensorOptions options;
  std::vector<std::uint8_t> clamps;
};

// The 45 cm example's clamps: sections 9 and 10 (40-50 cm) of both edges fixed.
std::vector<std::uint8_t> ClampsAtTheLoad() {
  return BothEdges([](int s) { return s == 9 || s == 10; });
}

std::vector<Point> Points(const SensorOptions& base) {
  std::vector<Point> points;
  for (double ratio : {1.0, 0.5, 0.3, 1.0 / 6.0, 0.1, 0.05, 0.03, 0.02, 0.01}) {
    SensorOptions o = base;
    o.layers[1].youngs_modulus = ratio * o.layers[0].youngs_modulus;
    points.push_back({"core_modulus", ratio, o, ClampsAtTheLoad()});
  }
  double total = 0.0;
  for (const Layer& layer : base.layers) total += layer.thickness;
  for (double mm : {1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0}) {
    SensorOptions o = base;
    for (Layer& layer : o.layers) layer.thickness *= 1e-3 * mm / total;
    points.push_back({"thickness", mm, o, ClampsAtTheLoad()});
  }
  // The load sits at 45 cm, between sections 9 and 10: k sections free on each side of it.
  for (int k = 0; k <= 9; ++k) {
    points.push_back(
        {"free_span", 10.0 * k, base, BothEdges([k](int s) { return s <= 9 - k || s >= 10 + k; })});
  }
  return points;
}

}  // namespace

int main(int argc, char** argv) {
  const int factor = argc > 1 ? std::atoi(argv[1]) : 1;
  if (factor < 1 || factor > 8) {
    std::fprintf(stderr, "plate_theory_sweep: mesh refinement factor must be 1 to 8\n");
    return 2;
  }
  SensorOptions base;
  base.load_cases[0].load_force = 0.042;
  base.elements_per_section *= factor;
  // Bilinear shear elements (element order 1), the meshes docs/model.md's figure was drawn with.
  base.element_order = 1;
  base.elements_across_width = 6 * factor;
  std::printf(
      "sweep,value,kirchhoff_peak_um,fsdt_peak_um,rzt_peak_um,fsdt_over_kirchhoff,"
      "rzt_over_kirchhoff,rzt_over_fsdt,profile_diff_kirchhoff_rzt,profile_diff_fsdt_rzt\n");
  const std::vector<Point> points = Points(base);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    std::fprintf(stderr, "%zu / %zu: %s = %g\n", i + 1, points.size(), p.sweep.c_str(), p.value);
    std::vector<std::vector<double>> profiles;  // Kirchhoff, FSDT, RZT
    for (PlateTheory theory : {PlateTheory::kKirchhoff, PlateTheory::kFsdt, PlateTheory::kRzt}) {
      SensorOptions o = p.options;
      o.theory = theory;
      const SensorModel model(o);
      profiles.push_back(Magnitudes(model, p.clamps));
    }
    const double k = Peak(profiles[0]);
    const double f = Peak(profiles[1]);
    const double r = Peak(profiles[2]);
    std::printf("%s,%.6g,%.6g,%.6g,%.6g,%.6f,%.6f,%.6f,%.6f,%.6f\n",
                p.sweep.c_str(),
                p.value,
                k * 1e6,
                f * 1e6,
                r * 1e6,
                f / k,
                r / k,
                r / f,
                ProfileDifference(profiles[0], profiles[2]),
                ProfileDifference(profiles[1], profiles[2]));
    std::fflush(stdout);
  }
  return 0;
}
