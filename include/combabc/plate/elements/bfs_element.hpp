#pragma once
// The Bogner-Fox-Schmit (BFS) rectangle: a conforming (C1) Kirchhoff plate element with the
// 4 degrees of freedom (w, w_x, w_y, w_xy) at each corner and tensor-product cubic Hermite shape
// functions (Bogner, Fox & Schmit 1965). Conforming, so its energy bounds converge monotonically,
// and free of shear locking because it has no transverse shear (docs/model.md, "Element").
//
// Local numbering: corner (a, b), a, b in {0, 1}, sits at (a hx, b hy) from the element's lower
// left corner; local dof 4 (a + 2 b) + k with k = 0 w, 1 w_x, 2 w_y, 3 w_xy.
#include <Eigen/Dense>

#include "combabc/plate/elements/element.hpp"

namespace combabc::plate {

inline constexpr int kBfsDofsPerNode = 4;
inline constexpr int kBfsElementDofs = 16;

// stiffness_real / _imag: integral of B^T D B, B = (d_xx, d_yy, 2 d_xy) N; mass_unit: N^T N.
ElementMatrices ComputeElementMatrices(double hx,
                                       double hy,
                                       const Eigen::Matrix3d& bending_real,
                                       const Eigen::Matrix3d& bending_imag);

// Shape function values at local coordinates (x, y) in [0, hx] x [0, hy].
ElementVector ShapeValues(double hx, double hy, double x, double y);

// Integral of N over the sub-rectangle [x0, x1] x [y0, y1] of the element (local coordinates):
// the consistent load vector of a unit uniform pressure on that part of the element.
ElementVector ShapeIntegral(double hx, double hy, double x0, double x1, double y0, double y1);

}  // namespace combabc::plate
