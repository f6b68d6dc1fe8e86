#include "combabc/plate/elements/rzt_element.hpp"

#include <array>

#include "combabc/plate/elements/mitc4_element.hpp"
#include "plate/elements/linear_basis.hpp"

namespace combabc::plate {
namespace {

// 2-point Gauss-Legendre on [0, 1]: exact for every product of bilinear functions and for the
// assumed shear strains (linear in one direction, constant in the other).
constexpr std::array<double, 2> kRztGaussPoint = {0.2113248654051871, 0.7886751345948129};
constexpr double kRztGaussWeight = 0.5;

using RztShearRows = Eigen::Matrix<double, 2, kRztElementDofs>;

int RztLocalDof(int a, int b, int k) { return kRztDofsPerNode * (a + 2 * b) + k; }

// Displacement-based shear strain rows at local (s, t) in [0, 1]^2 in direction `dir` (0 x,
// 1 y): row 0 w_,dir - theta_dir, row 1 psi_dir.
RztShearRows Shear(int dir, double hx, double hy, double s, double t) {
  RztShearRows rows = RztShearRows::Zero();
  for (int b = 0; b < 2; ++b) {
    for (int a = 0; a < 2; ++a) {
      const double n = Linear(a, s) * Linear(b, t);
      rows(0, RztLocalDof(a, b, 0)) =
          dir == 0 ? LinearSlope(a) / hx * Linear(b, t) : Linear(a, s) * LinearSlope(b) / hy;
      rows(0, RztLocalDof(a, b, 1 + dir)) = -n;
      rows(1, RztLocalDof(a, b, 3 + dir)) = n;
    }
  }
  return rows;
}

// Copies the w entries of a MITC4 vector (3 dofs per node) into the RZT layout.
ElementVector FromMitc4(const ElementVector& mitc4) {
  ElementVector n = ElementVector::Zero(kRztElementDofs);
  for (Eigen::Index corner = 0; corner < 4; ++corner) {
    n(kRztDofsPerNode * corner) = mitc4(kMitc4DofsPerNode * corner);
  }
  return n;
}

}  // namespace

ElementVector RztShapeValues(double hx, double hy, double x, double y) {
  return FromMitc4(Mitc4ShapeValues(hx, hy, x, y));
}

ElementVector RztShapeIntegral(double hx, double hy, double x0, double x1, double y0, double y1) {
  return FromMitc4(Mitc4ShapeIntegral(hx, hy, x0, x1, y0, y1));
}

ElementMatrices RztElementMatrices(double hx, double hy, const PlateSection& section) {
  // Tying points (Bathe & Dvorkin 1985): the x shear strains at the midpoints of the edges t = 0
  // and t = 1, interpolated linearly in t; the y ones at the midpoints of s = 0 and s = 1,
  // linearly in s.
  const RztShearRows bottom = Shear(0, hx, hy, 0.5, 0.0);
  const RztShearRows top = Shear(0, hx, hy, 0.5, 1.0);
  const RztShearRows left = Shear(1, hx, hy, 0.0, 0.5);
  const RztShearRows right = Shear(1, hx, hy, 1.0, 0.5);

  ElementMatrices m;
  m.stiffness_real.setZero(kRztElementDofs, kRztElementDofs);
  m.stiffness_imag.setZero(kRztElementDofs, kRztElementDofs);
  m.mass_unit.setZero(kRztElementDofs, kRztElementDofs);
  m.rotary_inertia.setZero(kRztElementDofs, kRztElementDofs);
  for (double s : kRztGaussPoint) {
    for (double t : kRztGaussPoint) {
      const double weight = kRztGaussWeight * kRztGaussWeight * hx * hy;
      // Curvatures of theta (rows 0-2) and psi (rows 3-5).
      Eigen::Matrix<double, 6, kRztElementDofs> bending =
          Eigen::Matrix<double, 6, kRztElementDofs>::Zero();
      Eigen::Matrix<double, kRztElementDofs, 1> n =
          Eigen::Matrix<double, kRztElementDofs, 1>::Zero();
      // (theta_a, psi_a) at the point, direction a = x (rows 0-1) and y (rows 2-3).
      Eigen::Matrix<double, 4, kRztElementDofs> rotation =
          Eigen::Matrix<double, 4, kRztElementDofs>::Zero();
      for (int b = 0; b < 2; ++b) {
        for (int a = 0; a < 2; ++a) {
          const double dx = LinearSlope(a) / hx * Linear(b, t);
          const double dy = Linear(a, s) * LinearSlope(b) / hy;
          for (int field = 0; field < 2; ++field) {  // theta, psi
            const int row = 3 * field;
            const int dof = 1 + 2 * field;
            bending(row + 0, RztLocalDof(a, b, dof)) = dx;
            bending(row + 1, RztLocalDof(a, b, dof + 1)) = dy;
            bending(row + 2, RztLocalDof(a, b, dof)) = dy;
            bending(row + 2, RztLocalDof(a, b, dof + 1)) = dx;
          }
          n(RztLocalDof(a, b, 0)) = Linear(a, s) * Linear(b, t);
          for (int dir = 0; dir < 2; ++dir) {
            const Eigen::Index row = 2 * static_cast<Eigen::Index>(dir);
            rotation(row, RztLocalDof(a, b, 1 + dir)) = Linear(a, s) * Linear(b, t);
            rotation(row + 1, RztLocalDof(a, b, 3 + dir)) = Linear(a, s) * Linear(b, t);
          }
        }
      }
      const RztShearRows shear_x = (1.0 - t) * bottom + t * top;
      const RztShearRows shear_y = (1.0 - s) * left + s * right;
      m.stiffness_real += weight * (bending.transpose() * section.zigzag_bending_real * bending +
                                    shear_x.transpose() * section.zigzag_shear_real * shear_x +
                                    shear_y.transpose() * section.zigzag_shear_real * shear_y);
      m.stiffness_imag += weight * (bending.transpose() * section.zigzag_bending_imag * bending +
                                    shear_x.transpose() * section.zigzag_shear_imag * shear_x +
                                    shear_y.transpose() * section.zigzag_shear_imag * shear_y);
      m.mass_unit += weight * n * n.transpose();
      for (Eigen::Index row : {0, 2}) {
        const auto rows = rotation.middleRows<2>(row);
        m.rotary_inertia += weight * rows.transpose() * section.zigzag_inertia * rows;
      }
    }
  }
  return m;
}

}  // namespace combabc::plate
