// Kirchhoff against first-order shear deformation theory and the refined zigzag theory on the
// sensor of the 45 cm example (docs/model.md, "Plate theories"): the un-normalised peak |w| and
// the largest difference of the normalised profiles from Kirchhoff's for a few clamp
// configurations, at the default mesh and finer ones (the FSDT and RZT elements are bilinear, so
// their mesh convergence is checked here too).
// Usage: plate_theory_comparison [max refinement factor, default 4]
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "combabc/plate/sensor_model.hpp"
#include "profile_metrics.hpp"

using combabc::plate::PlateTheory;
using combabc::plate::SensorModel;
using combabc::plate::SensorOptions;
using plate_examples::BothEdges;
using plate_examples::Magnitudes;
using plate_examples::Peak;
using plate_examples::ProfileDifference;

namespace {

struct Case {
  const char* name;
  std::vector<std::uint8_t> clamps;
};

}  // namespace

int main(int argc, char** argv) {
  const int max_factor = argc > 1 ? std::atoi(argv[1]) : 4;
  std::vector<Case> cases = {
      {"all free", BothEdges([](int) { return false; })},
      {"all fixed", BothEdges([](int) { return true; })},
      {"clamps at the load fixed (9, 10)", BothEdges([](int s) { return s == 9 || s == 10; })},
      {"alternating", BothEdges([](int s) { return s % 2 == 0; })},
      {"measured window free (10-16)", BothEdges([](int s) { return s < 10 || s > 16; })},
  };
  std::vector<std::uint8_t> one_side(36, 0);
  one_side[8] = one_side[9] = 1;  // edge 1 only
  cases.push_back({"one side fixed at the load", one_side});
  SensorOptions base;
  base.load_cases[0].load_force = 0.042;
  for (int factor = 1; factor <= max_factor; factor *= 2) {
    std::vector<std::vector<std::vector<double>>> profiles;  // theory, case
    for (PlateTheory theory : {PlateTheory::kKirchhoff, PlateTheory::kFsdt, PlateTheory::kRzt}) {
      SensorOptions o = base;
      o.theory = theory;
      o.elements_per_section *= factor;
      // Bilinear shear elements (element order 1), the meshes of docs/model.md's tables.
      o.element_order = 1;
      o.elements_across_width = 6 * factor;
      const auto t0 = std::chrono::steady_clock::now();
      const SensorModel model(o);
      const auto t1 = std::chrono::steady_clock::now();
      std::vector<double> full(model.num_outputs());
      model.ProfileFullSolve(cases[0].clamps, full);
      const auto t2 = std::chrono::steady_clock::now();
      std::printf("mesh %d x %d per section, %s: precompute %.2f s, one full solve %.1f ms\n",
                  o.elements_per_section,
                  o.ElementsAcrossWidth(),
                  combabc::ToString(theory),
                  std::chrono::duration<double>(t1 - t0).count(),
                  1e3 * std::chrono::duration<double>(t2 - t1).count());
      profiles.emplace_back();
      for (const Case& c : cases) profiles.back().push_back(Magnitudes(model, c.clamps));
    }
    std::printf("%-36s %12s %12s %12s %9s %9s %10s %10s\n",
                "configuration",
                "K (um)",
                "FSDT (um)",
                "RZT (um)",
                "FSDT / K",
                "RZT / K",
                "diff FSDT",
                "diff RZT");
    for (std::size_t k = 0; k < cases.size(); ++k) {
      const double pk = Peak(profiles[0][k]);
      const double pf = Peak(profiles[1][k]);
      const double pr = Peak(profiles[2][k]);
      std::printf("%-36s %12.4f %12.4f %12.4f %9.4f %9.4f %9.2f%% %9.2f%%\n",
                  cases[k].name,
                  pk * 1e6,
                  pf * 1e6,
                  pr * 1e6,
                  pf / pk,
                  pr / pk,
                  100.0 * ProfileDifference(profiles[1][k], profiles[0][k]),
                  100.0 * ProfileDifference(profiles[2][k], profiles[0][k]));
    }
  }
  return 0;
}
