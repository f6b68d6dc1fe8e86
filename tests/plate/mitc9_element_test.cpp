// The 9-node MITC9 / RZT9 elements (mitc9_element.hpp) on their own: rigid motions cost no strain
// energy; states of constant curvature and of constant transverse shear (patch tests) give the
// exact energy on an assembled mesh of unequal elements; the element has no zero-energy modes
// beyond the 3 rigid ones (the mixed interpolation adds none); its w interpolation reproduces
// quadratics. Convergence and the thin limit: fsdt_validation_test.cpp, rzt_validation_test.cpp.
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/elements/mitc9_element.hpp"

namespace combabc::plate {
namespace {

// The sensor's sandwich (rzt_validation_test.cpp): a soft core, so RZT's zigzag terms are not
// negligible and every block of the constitutive matrices is exercised.
PlateSection Sandwich() {
  Layer face;
  face.thickness = 1.5e-3;
  face.youngs_modulus = 30e6;
  face.poisson_ratio = 0.45;
  face.density = 1150.0;
  face.loss_factor = 0.1;
  Layer core = face;
  core.thickness = 1.0e-3;
  core.youngs_modulus = 5e6;
  core.loss_factor = 0.15;
  return EquivalentSingleLayer({face, core, face});
}

// Nodal values of a field given per node by (x, y) -> dofs of the node, element layout.
Eigen::VectorXd ElementField(Eigen::Index n,
                             double hx,
                             double hy,
                             const std::function<Eigen::VectorXd(double, double)>& field) {
  Eigen::VectorXd u(9 * n);
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) u.segment(n * (a + 3 * b), n) = field(0.5 * a * hx, 0.5 * b * hy);
  }
  return u;
}

// Rigid motions: w = 1; w = x with the slope-like dofs (phi, or theta in RZT) x = 1; w = y
// likewise. Zero energy to round-off: |K u| <= 1e-12 |K| |u| (the entries of K span the bending
// and shear scales, whose ratio is about (a / h)^2 ~ 1e3 here, far from losing 1e-12).
TEST(Mitc9Element, RigidMotionsCostNoEnergy) {
  const PlateSection section = Sandwich();
  const double hx = 0.012, hy = 0.007;
  for (PlateTheory theory : {PlateTheory::kFsdt, PlateTheory::kRzt}) {
    const int n = DofsPerNode(theory);
    const ElementMatrices m = theory == PlateTheory::kFsdt ? Mitc9ElementMatrices(hx, hy, section)
                                                           : Rzt9ElementMatrices(hx, hy, section);
    const std::vector<std::function<Eigen::VectorXd(double, double)>> motions = {
        [n](double, double) {
          Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
          d(0) = 1.0;
          return d;
        },
        [n](double x, double) {
          Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
          d(0) = x;
          d(1) = 1.0;
          return d;
        },
        [n](double, double y) {
          Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
          d(0) = y;
          d(2) = 1.0;
          return d;
        }};
    for (const auto& motion : motions) {
      const Eigen::VectorXd u = ElementField(n, hx, hy, motion);
      for (const ElementMatrix* k : {&m.stiffness_real, &m.stiffness_imag}) {
        const double scale = k->cwiseAbs().maxCoeff() * u.norm();
        EXPECT_LE((*k * u).norm(), 1e-12 * scale);
      }
    }
    // Exactly 3 zero-energy modes: the 4th smallest eigenvalue is a stiffness, not round-off
    // (measured 3e-7 (MITC9) and 2e-8 (RZT9) of the largest: soft bending of a 12 x 7 mm
    // element next to its shear stiffness; round-off sits near 1e-16, so the bound is 1e-11).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m.stiffness_real);
    const Eigen::VectorXd& lambda = eig.eigenvalues();
    EXPECT_LT(std::abs(lambda(2)), 1e-12 * lambda(lambda.size() - 1));
    std::printf("%s: eigenvalues 3, 4 / largest %.3g, %.3g\n",
                theory == PlateTheory::kFsdt ? "MITC9" : "RZT9",
                lambda(2) / lambda(lambda.size() - 1),
                lambda(3) / lambda(lambda.size() - 1));
    EXPECT_GT(lambda(3), 1e-11 * lambda(lambda.size() - 1));
  }
}

// Patch tests on an assembled plate of unequal elements (3 x 2 elements, sizes 1 : 2 : 1.5 by
// 1 : 3): the nodal values of an exact state, energy u^T K u = integral of its strain energy over
// the plate. Constant curvature (w = x^2 / 2 + x y + y^2 / 2 with rotations equal to the
// slopes, no shear): D : kappa kappa with kappa = (1, 1, 2); constant shear (w = x + 2 y, no
// rotation): S (1 + 4), with the FSDT shear stiffness S or RZT's zigzag_shear(0, 0). A wrong
// tying interpolation or quadrature misses these. Tolerance 1e-10: round-off of the assembly.
TEST(Mitc9Element, ConstantStrainPatchTests) {
  const PlateSection section = Sandwich();
  Grid grid;
  grid.x = {0.0, 0.005, 0.01, 0.02, 0.03, 0.0375, 0.045};
  grid.y = {0.0, 0.002, 0.004, 0.010, 0.016};
  const double area = 0.045 * 0.016;
  for (PlateTheory theory : {PlateTheory::kFsdt, PlateTheory::kRzt}) {
    const Plate plate(grid, section, 0.0, 0.0, theory, 2);
    ASSERT_EQ(plate.num_elements_x(), 3);
    ASSERT_EQ(plate.num_elements_y(), 2);
    const Constraints none = plate.NewConstraints();
    std::vector<int> free;
    const Eigen::SparseMatrix<double> k = plate.DynamicStiffness(none, 0.0, &free).real();
    ASSERT_EQ(static_cast<int>(free.size()), plate.num_dofs());
    const Eigen::Index n = plate.dofs_per_node();
    auto nodal = [&](const std::function<void(double, double, double*)>& field) {
      Eigen::VectorXd u = Eigen::VectorXd::Zero(plate.num_dofs());
      for (int i = 0; i <= grid.nx(); ++i) {
        for (int j = 0; j <= grid.ny(); ++j) field(grid.x[i], grid.y[j], &u(n * plate.Node(i, j)));
      }
      return u;
    };
    const Eigen::VectorXd bend = nodal([](double x, double y, double* d) {
      d[0] = 0.5 * x * x + x * y + 0.5 * y * y;
      d[1] = x + y;
      d[2] = x + y;
    });
    const Eigen::Vector3d kappa(1.0, 1.0, 2.0);
    const double bend_exact = kappa.dot(section.bending_real * kappa) * area;
    EXPECT_NEAR(bend.dot(k * bend) / bend_exact, 1.0, 1e-10);
    const Eigen::VectorXd shear = nodal([](double x, double y, double* d) { d[0] = x + 2.0 * y; });
    const double s =
        theory == PlateTheory::kFsdt ? section.shear_real : section.zigzag_shear_real(0, 0);
    EXPECT_NEAR(shear.dot(k * shear) / (s * 5.0 * area), 1.0, 1e-10);
  }
}

// The w interpolation reproduces a biquadratic field exactly, and the consistent load of a
// uniform pressure sums to the force (1e-12: round-off).
TEST(Mitc9Element, ShapeFunctionsReproduceQuadratics) {
  const double hx = 0.01, hy = 0.004;
  auto f = [](double x, double y) { return 1.0 + 3.0 * x - y + 40.0 * x * x + 70.0 * x * y * y; };
  Eigen::VectorXd u = Eigen::VectorXd::Zero(27);
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) u(Eigen::Index{3} * (a + 3 * b)) = f(0.5 * a * hx, 0.5 * b * hy);
  }
  for (double x : {0.0, 0.0013, 0.007}) {
    for (double y : {0.0005, 0.003}) {
      EXPECT_NEAR(Quad9ShapeValues(3, hx, hy, x, y).dot(u), f(x, y), 1e-12);
    }
  }
  EXPECT_NEAR(Quad9ShapeIntegral(5, hx, hy, 0.0, hx, 0.0, hy).sum(), hx * hy, 1e-12 * hx * hy);
}

}  // namespace
}  // namespace combabc::plate
