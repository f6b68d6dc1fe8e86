#include "combabc/plate/elements/mitc4_element.hpp"

#include <array>

#include "plate/elements/linear_basis.hpp"

namespace combabc::plate {
namespace {

// 2-point Gauss-Legendre on [0, 1]: exact for degree 3, enough for every product of bilinear
// functions and for the assumed shear strains (linear in one direction, constant in the other).
constexpr std::array<double, 2> kMitc4GaussPoint = {0.2113248654051871, 0.7886751345948129};
constexpr double kMitc4GaussWeight = 0.5;

int Mitc4LocalDof(int a, int b, int k) { return kMitc4DofsPerNode * (a + 2 * b) + k; }

// Displacement-based shear strain rows at local (s, t) in [0, 1]^2: gamma_x = w_x - phi_x
// (row 0) and gamma_y = w_y - phi_y (row 1).
Eigen::Matrix<double, 2, kMitc4ElementDofs> ShearRows(double hx, double hy, double s, double t) {
  Eigen::Matrix<double, 2, kMitc4ElementDofs> rows =
      Eigen::Matrix<double, 2, kMitc4ElementDofs>::Zero();
  for (int b = 0; b < 2; ++b) {
    for (int a = 0; a < 2; ++a) {
      const double n = Linear(a, s) * Linear(b, t);
      rows(0, Mitc4LocalDof(a, b, 0)) = LinearSlope(a) / hx * Linear(b, t);
      rows(0, Mitc4LocalDof(a, b, 1)) = -n;
      rows(1, Mitc4LocalDof(a, b, 0)) = Linear(a, s) * LinearSlope(b) / hy;
      rows(1, Mitc4LocalDof(a, b, 2)) = -n;
    }
  }
  return rows;
}

}  // namespace

ElementVector Mitc4ShapeValues(double hx, double hy, double x, double y) {
  ElementVector n = ElementVector::Zero(kMitc4ElementDofs);
  for (int b = 0; b < 2; ++b) {
    for (int a = 0; a < 2; ++a) n(Mitc4LocalDof(a, b, 0)) = Linear(a, x / hx) * Linear(b, y / hy);
  }
  return n;
}

ElementVector Mitc4ShapeIntegral(double hx, double hy, double x0, double x1, double y0, double y1) {
  ElementVector f = ElementVector::Zero(kMitc4ElementDofs);
  for (double gx : kMitc4GaussPoint) {
    for (double gy : kMitc4GaussPoint) {
      const double x = x0 + (x1 - x0) * gx;
      const double y = y0 + (y1 - y0) * gy;
      f += kMitc4GaussWeight * kMitc4GaussWeight * (x1 - x0) * (y1 - y0) *
           Mitc4ShapeValues(hx, hy, x, y);
    }
  }
  return f;
}

ElementMatrices Mitc4ElementMatrices(double hx, double hy, const PlateSection& section) {
  // Tying points of the assumed shear strains (Bathe & Dvorkin 1985): gamma_x at the midpoints of
  // the edges t = 0 and t = 1, interpolated linearly in t; gamma_y at the midpoints of s = 0 and
  // s = 1, linearly in s.
  const Eigen::Matrix<double, 2, kMitc4ElementDofs> bottom = ShearRows(hx, hy, 0.5, 0.0);
  const Eigen::Matrix<double, 2, kMitc4ElementDofs> top = ShearRows(hx, hy, 0.5, 1.0);
  const Eigen::Matrix<double, 2, kMitc4ElementDofs> left = ShearRows(hx, hy, 0.0, 0.5);
  const Eigen::Matrix<double, 2, kMitc4ElementDofs> right = ShearRows(hx, hy, 1.0, 0.5);

  ElementMatrices m;
  m.stiffness_real.setZero(kMitc4ElementDofs, kMitc4ElementDofs);
  m.stiffness_imag.setZero(kMitc4ElementDofs, kMitc4ElementDofs);
  m.mass_unit.setZero(kMitc4ElementDofs, kMitc4ElementDofs);
  m.rotary_inertia.setZero(kMitc4ElementDofs, kMitc4ElementDofs);
  for (double s : kMitc4GaussPoint) {
    for (double t : kMitc4GaussPoint) {
      const double weight = kMitc4GaussWeight * kMitc4GaussWeight * hx * hy;
      Eigen::Matrix<double, 3, kMitc4ElementDofs> bending =
          Eigen::Matrix<double, 3, kMitc4ElementDofs>::Zero();
      Eigen::Matrix<double, kMitc4ElementDofs, 1> n =
          Eigen::Matrix<double, kMitc4ElementDofs, 1>::Zero();
      Eigen::Matrix<double, kMitc4ElementDofs, 1> n_phi_x =
          Eigen::Matrix<double, kMitc4ElementDofs, 1>::Zero();
      Eigen::Matrix<double, kMitc4ElementDofs, 1> n_phi_y =
          Eigen::Matrix<double, kMitc4ElementDofs, 1>::Zero();
      for (int b = 0; b < 2; ++b) {
        for (int a = 0; a < 2; ++a) {
          const double dx = LinearSlope(a) / hx * Linear(b, t);
          const double dy = Linear(a, s) * LinearSlope(b) / hy;
          bending(0, Mitc4LocalDof(a, b, 1)) = dx;  // phi_x,x
          bending(1, Mitc4LocalDof(a, b, 2)) = dy;  // phi_y,y
          bending(2, Mitc4LocalDof(a, b, 1)) = dy;  // phi_x,y + phi_y,x
          bending(2, Mitc4LocalDof(a, b, 2)) = dx;
          n(Mitc4LocalDof(a, b, 0)) = Linear(a, s) * Linear(b, t);
          n_phi_x(Mitc4LocalDof(a, b, 1)) = Linear(a, s) * Linear(b, t);
          n_phi_y(Mitc4LocalDof(a, b, 2)) = Linear(a, s) * Linear(b, t);
        }
      }
      Eigen::Matrix<double, 2, kMitc4ElementDofs> shear;
      shear.row(0) = (1.0 - t) * bottom.row(0) + t * top.row(0);
      shear.row(1) = (1.0 - s) * left.row(1) + s * right.row(1);
      const Eigen::Matrix<double, kMitc4ElementDofs, kMitc4ElementDofs> shear_product =
          shear.transpose() * shear;
      m.stiffness_real += weight * (bending.transpose() * section.bending_real * bending +
                                    section.shear_real * shear_product);
      m.stiffness_imag += weight * (bending.transpose() * section.bending_imag * bending +
                                    section.shear_imag * shear_product);
      m.mass_unit += weight * n * n.transpose();
      m.rotary_inertia += weight * section.rotary_inertia *
                          (n_phi_x * n_phi_x.transpose() + n_phi_y * n_phi_y.transpose());
    }
  }
  return m;
}

}  // namespace combabc::plate
