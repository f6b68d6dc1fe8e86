#pragma once
// The MITC4 rectangle for first-order shear deformation (Reissner-Mindlin) plates: bilinear w and
// rotations at the 4 corners, dofs (w, phi_x, phi_y) per corner, with the transverse shear strains
// interpolated from their values at the edge midpoints (the mixed interpolation of Bathe &
// Dvorkin, Int. J. Numer. Meth. Eng. 21 (1985) 367-383). The assumed shear strain field is what
// removes shear locking: as the thickness goes to zero the element returns the Kirchhoff answer
// on a fixed mesh (tests/plate/fsdt_validation_test.cpp).
//
// Kinematics: in-plane displacements -z (phi_x, phi_y), so phi equals the slope (w_x, w_y) when
// the shear strains gamma = (w_x - phi_x, w_y - phi_y) vanish; curvatures (phi_x,x, phi_y,y,
// phi_x,y + phi_y,x) pair with the same bending stiffness D as Kirchhoff's (w_xx, w_yy, 2 w_xy).
// Local dof 3 (a + 2 b) + k for corner (a, b) (element.hpp).
#include "combabc/plate/elements/element.hpp"
#include "combabc/plate/elements/laminate.hpp"

namespace combabc::plate {

inline constexpr int kMitc4DofsPerNode = 3;
inline constexpr int kMitc4ElementDofs = 12;

// stiffness: bending (2 x 2 Gauss, exact) plus the assumed-strain shear (2 x 2 Gauss, exact for
// it); mass_unit: the consistent w mass, integral of N^T N; rotary_inertia: the consistent mass of
// the rotations, PlateSection::rotary_inertia times the integral of N^T N on phi_x and phi_y.
ElementMatrices Mitc4ElementMatrices(double hx, double hy, const PlateSection& section);

// Values of the w shape functions at local (x, y) in [0, hx] x [0, hy] (zero on rotation dofs).
ElementVector Mitc4ShapeValues(double hx, double hy, double x, double y);

// Integral of the w shape functions over the sub-rectangle [x0, x1] x [y0, y1] (local
// coordinates): the consistent load vector of a unit pressure on that part of the element.
ElementVector Mitc4ShapeIntegral(double hx, double hy, double x0, double x1, double y0, double y1);

}  // namespace combabc::plate
