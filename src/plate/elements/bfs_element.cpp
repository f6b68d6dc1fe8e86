#include "combabc/plate/elements/bfs_element.hpp"

#include <array>

namespace combabc::plate {
namespace {

// Cubic Hermite basis on [0, h]; index 2 a + p is the value (p = 0) or slope (p = 1) function of
// end a. Returns values and the first two x-derivatives at s = x / h.
struct Hermite {
  std::array<double, 4> value;
  std::array<double, 4> d1;
  std::array<double, 4> d2;
};

Hermite HermiteAt(double h, double x) {
  const double s = x / h;
  const double s2 = s * s;
  const double s3 = s2 * s;
  Hermite r;
  r.value = {
      1.0 - 3.0 * s2 + 2.0 * s3, h * (s - 2.0 * s2 + s3), 3.0 * s2 - 2.0 * s3, h * (s3 - s2)};
  r.d1 = {(-6.0 * s + 6.0 * s2) / h,
          1.0 - 4.0 * s + 3.0 * s2,
          (6.0 * s - 6.0 * s2) / h,
          3.0 * s2 - 2.0 * s};
  r.d2 = {(-6.0 + 12.0 * s) / (h * h),
          (-4.0 + 6.0 * s) / h,
          (6.0 - 12.0 * s) / (h * h),
          (6.0 * s - 2.0) / h};
  return r;
}

// 4-point Gauss-Legendre on [0, 1]: exact for degree 7, enough for every product used here
// (N^T N is degree 6 in each direction).
constexpr std::array<double, 4> kBfsGaussPoint = {
    0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
constexpr std::array<double, 4> kBfsGaussWeight = {
    0.1739274225813185, 0.3260725774186815, 0.3260725774186815, 0.1739274225813185};

int BfsLocalDof(int a, int b, int k) { return kBfsDofsPerNode * (a + 2 * b) + k; }

}  // namespace

ElementVector ShapeValues(double hx, double hy, double x, double y) {
  const Hermite hx_basis = HermiteAt(hx, x);
  const Hermite hy_basis = HermiteAt(hy, y);
  ElementVector n(kBfsElementDofs);
  for (int b = 0; b < 2; ++b) {
    for (int a = 0; a < 2; ++a) {
      for (int k = 0; k < kBfsDofsPerNode; ++k) {
        const int p = k & 1;
        const int q = k >> 1;
        n(BfsLocalDof(a, b, k)) = hx_basis.value[2 * a + p] * hy_basis.value[2 * b + q];
      }
    }
  }
  return n;
}

ElementVector ShapeIntegral(double hx, double hy, double x0, double x1, double y0, double y1) {
  ElementVector f = ElementVector::Zero(kBfsElementDofs);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double x = x0 + (x1 - x0) * kBfsGaussPoint[i];
      const double y = y0 + (y1 - y0) * kBfsGaussPoint[j];
      f += kBfsGaussWeight[i] * kBfsGaussWeight[j] * (x1 - x0) * (y1 - y0) *
           ShapeValues(hx, hy, x, y);
    }
  }
  return f;
}

ElementMatrices ComputeElementMatrices(double hx,
                                       double hy,
                                       const Eigen::Matrix3d& bending_real,
                                       const Eigen::Matrix3d& bending_imag) {
  ElementMatrices m;
  m.stiffness_real.setZero(kBfsElementDofs, kBfsElementDofs);
  m.stiffness_imag.setZero(kBfsElementDofs, kBfsElementDofs);
  m.mass_unit.setZero(kBfsElementDofs, kBfsElementDofs);
  // Kirchhoff theory here neglects rotary inertia (thin plates: h^2 / 12 against wavelength^2).
  m.rotary_inertia.setZero(kBfsElementDofs, kBfsElementDofs);
  for (int i = 0; i < 4; ++i) {
    const Hermite bx = HermiteAt(hx, hx * kBfsGaussPoint[i]);
    for (int j = 0; j < 4; ++j) {
      const Hermite by = HermiteAt(hy, hy * kBfsGaussPoint[j]);
      const double weight = kBfsGaussWeight[i] * kBfsGaussWeight[j] * hx * hy;
      Eigen::Matrix<double, 3, kBfsElementDofs> b_matrix;
      ElementVector n(kBfsElementDofs);
      for (int b = 0; b < 2; ++b) {
        for (int a = 0; a < 2; ++a) {
          for (int k = 0; k < kBfsDofsPerNode; ++k) {
            const int ix = 2 * a + (k & 1);
            const int iy = 2 * b + (k >> 1);
            const int d = BfsLocalDof(a, b, k);
            n(d) = bx.value[ix] * by.value[iy];
            b_matrix(0, d) = bx.d2[ix] * by.value[iy];
            b_matrix(1, d) = bx.value[ix] * by.d2[iy];
            b_matrix(2, d) = 2.0 * bx.d1[ix] * by.d1[iy];
          }
        }
      }
      m.stiffness_real += weight * b_matrix.transpose() * bending_real * b_matrix;
      m.stiffness_imag += weight * b_matrix.transpose() * bending_imag * b_matrix;
      m.mass_unit += weight * n * n.transpose();
    }
  }
  return m;
}

}  // namespace combabc::plate
