#include "combabc/plate/elements/mitc9_element.hpp"

#include <array>
#include <cmath>

namespace combabc::plate {
namespace {

// 3-point Gauss-Legendre on [-1, 1]: exact for degree 5, so for every product of biquadratic
// functions and their derivatives on a rectangle (at most quartic in one variable) and for the
// assumed shear strains (linear in one direction, quadratic in the other).
constexpr std::array<double, 3> kMitc9GaussPoint = {-0.7745966692414834, 0.0, 0.7745966692414834};
constexpr std::array<double, 3> kMitc9GaussWeight = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};

// Tying coordinates (Bucalem & Bathe 1993): the 2-point Gauss abscissa for the direction of the
// strain, the 3-point ones across it.
const double kTieLinear = 1.0 / std::sqrt(3.0);
const double kTieQuadratic = std::sqrt(3.0 / 5.0);

// Quadratic Lagrange basis on the nodes r = -1, 0, 1: value and derivative of node a at r.
double Lagrange(int a, double r) {
  if (a == 0) return 0.5 * r * (r - 1.0);
  if (a == 1) return 1.0 - r * r;
  return 0.5 * r * (r + 1.0);
}
double LagrangeSlope(int a, double r) {
  if (a == 0) return r - 0.5;
  if (a == 1) return -2.0 * r;
  return r + 0.5;
}

// Lagrange basis of the tying points: linear through -+kTieLinear (i = 0, 1) and quadratic through
// -kTieQuadratic, 0, kTieQuadratic (j = 0, 1, 2).
double TieLinear(int i, double r) {
  return i == 0 ? 0.5 * (1.0 - r / kTieLinear) : 0.5 * (1.0 + r / kTieLinear);
}
double TieQuadratic(int j, double s) {
  const double b2 = kTieQuadratic * kTieQuadratic;
  if (j == 0) return 0.5 * s * (s - kTieQuadratic) / b2;
  if (j == 1) return 1.0 - s * s / b2;
  return 0.5 * s * (s + kTieQuadratic) / b2;
}

// One theory's layout: N dofs per node, F = (N - 1) / 2 fields of slope-like dofs (FSDT: phi;
// RZT: theta, then psi). Field f, direction d (0 x, 1 y) is dof 1 + 2 f + d.
template <int N>
struct Quad9 {
  static constexpr int kDofs = kQuad9Nodes * N;
  static constexpr int kFields = (N - 1) / 2;
  using Row = Eigen::Matrix<double, 1, kDofs>;
  using Shear = Eigen::Matrix<double, kFields, kDofs>;
  using Bending = Eigen::Matrix<double, 3 * kFields, kDofs>;
  using FieldMatrix = Eigen::Matrix<double, kFields, kFields>;
  using BendingMatrix = Eigen::Matrix<double, 3 * kFields, 3 * kFields>;

  double hx, hy;

  static int Dof(int a, int b, int k) { return N * (a + 3 * b) + k; }

  // Displacement-based shear strains of direction d at natural (r, s): row 0 w_,d - (field 0)_d,
  // row 1 (RZT) psi_d.
  Shear DisplacementShear(int d, double r, double s) const {
    Shear rows = Shear::Zero();
    for (int b = 0; b < 3; ++b) {
      for (int a = 0; a < 3; ++a) {
        const double n = Lagrange(a, r) * Lagrange(b, s);
        rows(0, Dof(a, b, 0)) = d == 0 ? 2.0 / hx * LagrangeSlope(a, r) * Lagrange(b, s)
                                       : 2.0 / hy * Lagrange(a, r) * LagrangeSlope(b, s);
        rows(0, Dof(a, b, 1 + d)) = -n;
        if constexpr (kFields == 2) rows(1, Dof(a, b, 3 + d)) = n;
      }
    }
    return rows;
  }

  // The assumed (MITC9) shear strains of direction d at (r, s), from the tying values.
  Shear AssumedShear(int d, const std::array<Shear, 6>& tied, double r, double s) const {
    Shear rows = Shear::Zero();
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 3; ++j) {
        // Direction x: linear in r, quadratic in s; direction y: the transpose.
        const double h =
            d == 0 ? TieLinear(i, r) * TieQuadratic(j, s) : TieLinear(i, s) * TieQuadratic(j, r);
        rows += h * tied[3 * i + j];
      }
    }
    return rows;
  }

  std::array<Shear, 6> TyingValues(int d) const {
    std::array<Shear, 6> tied;
    for (int i = 0; i < 2; ++i) {
      const double linear = i == 0 ? -kTieLinear : kTieLinear;
      for (int j = 0; j < 3; ++j) {
        const double quadratic = (j - 1) * kTieQuadratic;
        tied[3 * i + j] = d == 0 ? DisplacementShear(0, linear, quadratic)
                                 : DisplacementShear(1, quadratic, linear);
      }
    }
    return tied;
  }

  ElementMatrices Matrices(const BendingMatrix& bending_real,
                           const BendingMatrix& bending_imag,
                           const FieldMatrix& shear_real,
                           const FieldMatrix& shear_imag,
                           const FieldMatrix& inertia) const {
    const std::array<Shear, 6> tied_x = TyingValues(0);
    const std::array<Shear, 6> tied_y = TyingValues(1);
    ElementMatrices m;
    m.stiffness_real.setZero(kDofs, kDofs);
    m.stiffness_imag.setZero(kDofs, kDofs);
    m.mass_unit.setZero(kDofs, kDofs);
    m.rotary_inertia.setZero(kDofs, kDofs);
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        const double r = kMitc9GaussPoint[p];
        const double s = kMitc9GaussPoint[q];
        const double weight = kMitc9GaussWeight[p] * kMitc9GaussWeight[q] * 0.25 * hx * hy;
        Bending bending = Bending::Zero();
        Row n = Row::Zero();
        // The slope-like fields of each direction d at the point (for the rotary inertia).
        std::array<Shear, 2> slopes;
        slopes[0].setZero();
        slopes[1].setZero();
        for (int b = 0; b < 3; ++b) {
          for (int a = 0; a < 3; ++a) {
            const double dx = 2.0 / hx * LagrangeSlope(a, r) * Lagrange(b, s);
            const double dy = 2.0 / hy * Lagrange(a, r) * LagrangeSlope(b, s);
            const double value = Lagrange(a, r) * Lagrange(b, s);
            for (int f = 0; f < kFields; ++f) {
              const int fx = 1 + 2 * f;  // the field's x dof; fx + 1 its y dof
              bending(3 * f + 0, Dof(a, b, fx)) = dx;
              bending(3 * f + 1, Dof(a, b, fx + 1)) = dy;
              bending(3 * f + 2, Dof(a, b, fx)) = dy;
              bending(3 * f + 2, Dof(a, b, fx + 1)) = dx;
              slopes[0](f, Dof(a, b, fx)) = value;
              slopes[1](f, Dof(a, b, fx + 1)) = value;
            }
            n(Dof(a, b, 0)) = value;
          }
        }
        const Shear shear_x = AssumedShear(0, tied_x, r, s);
        const Shear shear_y = AssumedShear(1, tied_y, r, s);
        m.stiffness_real += weight * (bending.transpose() * bending_real * bending +
                                      shear_x.transpose() * shear_real * shear_x +
                                      shear_y.transpose() * shear_real * shear_y);
        m.stiffness_imag += weight * (bending.transpose() * bending_imag * bending +
                                      shear_x.transpose() * shear_imag * shear_x +
                                      shear_y.transpose() * shear_imag * shear_y);
        m.mass_unit += weight * n.transpose() * n;
        for (const Shear& rows : slopes) {
          m.rotary_inertia += weight * rows.transpose() * inertia * rows;
        }
      }
    }
    return m;
  }
};

}  // namespace

ElementMatrices Mitc9ElementMatrices(double hx, double hy, const PlateSection& section) {
  const Eigen::Matrix<double, 1, 1> shear_real(section.shear_real);
  const Eigen::Matrix<double, 1, 1> shear_imag(section.shear_imag);
  const Eigen::Matrix<double, 1, 1> inertia(section.rotary_inertia);
  return Quad9<3>{hx, hy}.Matrices(
      section.bending_real, section.bending_imag, shear_real, shear_imag, inertia);
}

ElementMatrices Rzt9ElementMatrices(double hx, double hy, const PlateSection& section) {
  return Quad9<5>{hx, hy}.Matrices(section.zigzag_bending_real,
                                   section.zigzag_bending_imag,
                                   section.zigzag_shear_real,
                                   section.zigzag_shear_imag,
                                   section.zigzag_inertia);
}

ElementVector Quad9ShapeValues(int dofs_per_node, double hx, double hy, double x, double y) {
  ElementVector n = ElementVector::Zero(static_cast<Eigen::Index>(kQuad9Nodes) * dofs_per_node);
  const double r = 2.0 * x / hx - 1.0;
  const double s = 2.0 * y / hy - 1.0;
  for (int b = 0; b < 3; ++b) {
    for (int a = 0; a < 3; ++a) {
      n(static_cast<Eigen::Index>(dofs_per_node) * (a + 3 * b)) = Lagrange(a, r) * Lagrange(b, s);
    }
  }
  return n;
}

ElementVector Quad9ShapeIntegral(
    int dofs_per_node, double hx, double hy, double x0, double x1, double y0, double y1) {
  // Biquadratic integrand: 3-point Gauss on the sub-rectangle is exact.
  ElementVector f = ElementVector::Zero(static_cast<Eigen::Index>(kQuad9Nodes) * dofs_per_node);
  for (int p = 0; p < 3; ++p) {
    for (int q = 0; q < 3; ++q) {
      const double x = x0 + 0.5 * (x1 - x0) * (1.0 + kMitc9GaussPoint[p]);
      const double y = y0 + 0.5 * (y1 - y0) * (1.0 + kMitc9GaussPoint[q]);
      f += kMitc9GaussWeight[p] * kMitc9GaussWeight[q] * 0.25 * (x1 - x0) * (y1 - y0) *
           Quad9ShapeValues(dofs_per_node, hx, hy, x, y);
    }
  }
  return f;
}

}  // namespace combabc::plate
