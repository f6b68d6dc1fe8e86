#pragma once
// The RZT4 rectangle for the refined zigzag theory (laminate.hpp, PlateSection::zigzag_*;
// Tessler, Di Sciuva & Gherlone 2009/2010): bilinear w, rotations theta and zigzag amplitudes psi
// at the 4 corners, dofs (w, theta_x, theta_y, psi_x, psi_y) per corner. Both transverse shear
// strains of each direction, w_,a - theta_a and psi_a, are interpolated from their values at the
// edge midpoints as in MITC4 (mitc4_element.hpp; Bathe & Dvorkin 1985), so the shear terms and
// their coupling see one consistent assumed field and the element does not lock: as the
// thickness goes to zero psi and the shear strains vanish and the element returns the Kirchhoff
// answer on a fixed mesh (tests/plate/rzt_validation_test.cpp). The bending part pairs the
// curvatures of theta and of psi through the 6 x 6 zigzag_bending matrix.
// Local dof 5 (a + 2 b) + k for corner (a, b) (element.hpp).
#include "combabc/plate/elements/element.hpp"
#include "combabc/plate/elements/laminate.hpp"

namespace combabc::plate {

inline constexpr int kRztDofsPerNode = 5;
inline constexpr int kRztElementDofs = 20;

// stiffness: bending (2 x 2 Gauss, exact) plus the assumed-strain shear (2 x 2 Gauss, exact for
// it); mass_unit: the consistent w mass, integral of N^T N; rotary_inertia: the consistent mass of
// (theta, psi) with PlateSection::zigzag_inertia.
ElementMatrices RztElementMatrices(double hx, double hy, const PlateSection& section);

// Values of the w shape functions at local (x, y) in [0, hx] x [0, hy] (zero on the other dofs).
ElementVector RztShapeValues(double hx, double hy, double x, double y);

// Integral of the w shape functions over the sub-rectangle [x0, x1] x [y0, y1] (local
// coordinates): the consistent load vector of a unit pressure on that part of the element.
ElementVector RztShapeIntegral(double hx, double hy, double x0, double x1, double y0, double y1);

}  // namespace combabc::plate
