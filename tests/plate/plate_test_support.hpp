#pragma once
// Helpers shared by the plate's tests: random clamp configurations and the relative difference
// of two profiles (the sensor model's tests), and for the theories' validation tests
// (fsdt_validation_test.cpp, rzt_validation_test.cpp) the default sensor's laminate and the simply
// supported square under a uniform or a sinusoidal load, whose closed-form and exact 3D solutions
// (layered_exact.hpp) are the references.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/elements/laminate.hpp"
#include "support/test_support.hpp"

namespace combabc::plate::testing {

using combabc::testing::Repetitions;

// n clamps, each fixed (1) or free (0) with probability 1/2.
inline std::vector<std::uint8_t> RandomClamps(std::mt19937_64& rng, int n) {
  std::vector<std::uint8_t> c(n);
  for (auto& v : c) v = static_cast<std::uint8_t>(rng() & 1);
  return c;
}

// max |a - b| relative to max |b|.
inline double MaxRelativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double diff = 0.0;
  double scale = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    diff = std::max(diff, std::abs(a[k] - b[k]));
    scale = std::max(scale, std::abs(b[k]));
  }
  return diff / scale;
}

// The default sensor's laminate (docs/model.md): faces 1.5 mm, E 30 MPa; core 1.0 mm, E 5 MPa;
// with its loss factors (faces 0.10, core 0.15) only where asked: the FE checks are static,
// elastic ones.
inline std::vector<Layer> SensorLaminate(bool lossy = false) {
  Layer face;
  face.thickness = 1.5e-3;
  face.youngs_modulus = 30e6;
  face.poisson_ratio = 0.45;
  face.density = 1150.0;
  face.loss_factor = lossy ? 0.10 : 0.0;
  Layer core = face;
  core.thickness = 1.0e-3;
  core.youngs_modulus = 5e6;
  core.density = 1100.0;
  core.loss_factor = lossy ? 0.15 : 0.0;
  return {face, core, face};
}

// All four edges simply supported (the hard support of the Navier solutions).
inline Constraints SimplySupported(const Plate& plate) {
  Constraints c = plate.NewConstraints();
  for (Edge edge : {Edge::kLeft, Edge::kBottom, Edge::kRight, Edge::kTop}) {
    c.AddEdgeSupport(edge, Support::kSimplySupported);
  }
  return c;
}

// Static centre deflection of the simply supported square of side `side` on a mesh of n x n
// elements of element order `order` (plate.hpp) under unit uniform pressure.
inline double UniformCentre(
    PlateTheory theory, const PlateSection& section, double side, int n, int order = 1) {
  const Plate plate(
      UniformGrid(side, side, order * n, order * n), section, 0.0, 0.0, theory, order);
  Load load;
  load.x = load.y = 0.5 * side;
  load.patch_length = load.patch_width = side;
  load.force = side * side;
  const Eigen::VectorXd u = plate.SolveStatic(SimplySupported(plate), load);
  return plate.Deflection(u, 0.5 * side, 0.5 * side);
}

// A load vector of the pressure sin(pi x / a) sin(pi y / a) by 3 x 3 Gauss points per grid
// interval (the discretisation error of the load is then far below the element's, of either
// order).
inline Eigen::VectorXd SinusoidalLoad(const Plate& plate, double side) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(plate.num_dofs());
  const double points[3] = {0.1127016653792583, 0.5, 0.8872983346207417};
  const double weights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
  const Grid& grid = plate.grid();
  for (int ex = 0; ex < grid.nx(); ++ex) {
    for (int ey = 0; ey < grid.ny(); ++ey) {
      const double hx = grid.x[ex + 1] - grid.x[ex];
      const double hy = grid.y[ey + 1] - grid.y[ey];
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          const double x = grid.x[ex] + points[i] * hx;
          const double y = grid.y[ey] + points[j] * hy;
          const double p = std::sin(M_PI * x / side) * std::sin(M_PI * y / side);
          int dofs[kMaxElementDofs];
          ElementVector row;
          plate.InterpolationRow(x, y, dofs, &row);
          for (int k = 0; k < plate.element_dofs(); ++k) {
            f(dofs[k]) += weights[i] * weights[j] * hx * hy * p * row(k);
          }
        }
      }
    }
  }
  return f;
}

// Static centre deflection of the simply supported square of side `side` on a mesh of n x n
// elements of element order `order` under the unit sinusoidal load (real part: SolveHarmonic at
// 0 Hz).
inline double SinusoidalCentre(
    PlateTheory theory, const PlateSection& section, double side, int n, int order = 1) {
  const Plate plate(
      UniformGrid(side, side, order * n, order * n), section, 0.0, 0.0, theory, order);
  const Eigen::VectorXcd u =
      plate.SolveHarmonic(SimplySupported(plate), SinusoidalLoad(plate, side), 0.0);
  return plate.Deflection(u, 0.5 * side, 0.5 * side).real();
}

// The quadratic elements (element order 2) of `theory` against a closed form `exact(side)` of
// the SSSS square under the sinusoidal load, 2, 4 and 8 elements per side: the error must fall by
// more than 4x per halving (faster than the bilinear elements' O(h^2); the measured rates are
// printed for docs/model.md) and end below 0.05 % at 8 x 8.
template <class Exact>
void ExpectQuadraticConvergence(PlateTheory theory,
                                const char* element,
                                const PlateSection& section,
                                const Exact& exact) {
  for (double side : {0.01, 0.04, 0.08}) {
    const double reference = exact(side);
    double previous = 0.0;
    for (int n : {2, 4, 8}) {
      const double fe = SinusoidalCentre(theory, section, side, n, 2);
      const double error = std::abs(fe / reference - 1.0);
      std::printf("a = %.0f mm, %d x %d %s: FE / closed form %.8f, error ratio %.1f\n",
                  side * 1e3,
                  n,
                  n,
                  element,
                  fe / reference,
                  n > 2 ? previous / error : 0.0);
      if (n > 2) {
        EXPECT_GT(previous / error, 4.0) << element << " " << n;
      }
      previous = error;
    }
    EXPECT_LT(previous, 5e-4) << element;
  }
}

}  // namespace combabc::plate::testing
