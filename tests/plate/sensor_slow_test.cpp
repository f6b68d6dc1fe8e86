// The fast path against the full sparse solve at the default (converged) mesh, over many random
// configurations. Labelled `slow`: each full solve factors about 13,000 complex unknowns.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "combabc/plate/sensor_model.hpp"

namespace combabc::plate {
namespace {

constexpr double kFastPathTol = 1e-8;  // relative to the profile's maximum (issue)

TEST(PlateSensorSlow, FastPathEqualsFullSolveDefaultMesh) {
  const SensorModel model{SensorOptions{}};
  std::mt19937_64 rng(5);
  std::vector<double> fast(model.num_outputs());
  std::vector<double> full(model.num_outputs());
  double worst = 0.0;
  constexpr int kConfigurations = 200;
  for (int i = 0; i < kConfigurations; ++i) {
    std::vector<std::uint8_t> clamps(model.num_clamps());
    for (auto& v : clamps) v = static_cast<std::uint8_t>(rng() & 1);
    model.Profile(clamps, fast);
    model.ProfileFullSolve(clamps, full);
    double diff = 0.0;
    for (std::size_t k = 0; k < fast.size(); ++k) {
      diff = std::max(diff, std::abs(fast[k] - full[k]));
    }
    worst = std::max(worst, diff / *std::max_element(full.begin(), full.end()));
  }
  std::printf("default mesh: worst relative difference over %d configurations: %.2e\n",
              kConfigurations,
              worst);
  EXPECT_LT(worst, kFastPathTol);
}

}  // namespace
}  // namespace combabc::plate
