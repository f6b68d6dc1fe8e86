// The peak |w| with every clamp fixed (the configuration whose clamped/free edges and load patch
// the shear theories resolve worst) for bilinear (element order 1) and 9-node quadratic (order 2)
// elements of FSDT and RZT on a list of meshes (docs/model.md, "Mesh convergence of the shear
// theories"), with the precompute time and the nodes per cross-section, which set the fast
// path's cost. Default load 0.042 N as plate_theory_comparison.
// Usage: plate_element_order_study [theory order along across]... (default: RZT, order 2 at
// 5 x 3, 10 x 3, 5 x 6, 10 x 6 per section)
#include <algorithm>
#include <chrono>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "combabc/plate/sensor_model.hpp"

using combabc::plate::PlateTheory;
using combabc::plate::SensorModel;
using combabc::plate::SensorOptions;

namespace {

struct Mesh {
  PlateTheory theory;
  int order, along, across;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<Mesh> meshes;
  for (int k = 1; k + 3 < argc; k += 4) {
    const auto theory = combabc::ParseEnum<PlateTheory>(argv[k]);
    if (!theory) {
      std::fprintf(stderr, "unknown theory %s\n", argv[k]);
      return 2;
    }
    meshes.push_back(
        {*theory, std::atoi(argv[k + 1]), std::atoi(argv[k + 2]), std::atoi(argv[k + 3])});
  }
  if (meshes.empty()) {
    for (const auto& [along, across] :
         {std::pair{5, 3}, std::pair{10, 3}, std::pair{5, 6}, std::pair{10, 6}}) {
      meshes.push_back({PlateTheory::kRzt, 2, along, across});
    }
  }
  for (const Mesh& mesh : meshes) {
    SensorOptions o;
    o.load_cases[0].load_force = 0.042;
    o.theory = mesh.theory;
    o.element_order = mesh.order;
    o.elements_per_section = mesh.along;
    o.elements_across_width = mesh.across;
    const auto t0 = std::chrono::steady_clock::now();
    const SensorModel model(o);
    const auto t1 = std::chrono::steady_clock::now();
    const std::vector<std::uint8_t> clamps(static_cast<std::size_t>(model.num_clamps()), 1);
    std::vector<std::complex<double>> w(static_cast<std::size_t>(model.num_outputs()));
    model.ComplexProfile(clamps, w);
    double peak = 0.0;
    for (const auto& v : w) peak = std::max(peak, std::abs(v));
    std::printf(
        "%s order %d, %d x %d per section (%d node lines across): all fixed peak %.4f um "
        "(precompute %.2f s)\n",
        combabc::ToString(mesh.theory),
        mesh.order,
        mesh.along,
        mesh.across,
        mesh.order * mesh.across + 1,
        peak * 1e6,
        std::chrono::duration<double>(t1 - t0).count());
  }
  return 0;
}
