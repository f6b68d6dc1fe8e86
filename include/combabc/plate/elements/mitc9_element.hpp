#pragma once
// The 9-node quadratic rectangles of the shear theories (element order 2, plate.hpp): biquadratic
// w, rotations (and, in RZT, zigzag amplitudes) at the corners, the mid-sides and the centre;
// node (a, b), a, b in {0, 1, 2}, at (a hx / 2, b hy / 2) from the element's lower left corner,
// local dof n (a + 3 b) + k with n = DofsPerNode (element.hpp).
//
// Transverse shear by the MITC9 mixed interpolation (Bucalem & Bathe, Int. J. Numer. Meth. Eng.
// 36 (1993) 3729-3754, plate form): gamma_x is sampled from the displacement field at the 6
// tying points r = +-1/sqrt(3), s in {-sqrt(3/5), 0, sqrt(3/5)} (natural coordinates in
// [-1, 1]^2) and interpolated linearly in r and quadratically in s through them; gamma_y at the
// transposed points. The assumed field is what removes shear locking: as the thickness goes to
// zero the element returns the Kirchhoff answer on a fixed mesh (tests/plate/mitc9_test.cpp).
// RZT9 ties both shear strain sets of the refined zigzag theory (w_,a - theta_a and psi_a) at the
// same points, as RZT4 does with MITC4 (rzt_element.hpp). Bending: full 3 x 3 Gauss.
#include "combabc/plate/elements/element.hpp"
#include "combabc/plate/elements/laminate.hpp"

namespace combabc::plate {

inline constexpr int kQuad9Nodes = 9;

// First-order shear deformation theory, dofs (w, phi_x, phi_y) per node (as MITC4).
// stiffness: bending plus assumed-strain shear (3 x 3 Gauss, exact for both on a rectangle);
// mass_unit: the consistent w mass; rotary_inertia: PlateSection::rotary_inertia times the
// consistent mass of phi_x and phi_y.
ElementMatrices Mitc9ElementMatrices(double hx, double hy, const PlateSection& section);

// Refined zigzag theory, dofs (w, theta_x, theta_y, psi_x, psi_y) per node (as RZT4).
ElementMatrices Rzt9ElementMatrices(double hx, double hy, const PlateSection& section);

// Values of the w shape functions at local (x, y) in [0, hx] x [0, hy] (zero on the other dofs)
// for `dofs_per_node` dofs at each of the 9 nodes.
ElementVector Quad9ShapeValues(int dofs_per_node, double hx, double hy, double x, double y);

// Integral of the w shape functions over the sub-rectangle [x0, x1] x [y0, y1] (local
// coordinates): the consistent load vector of a unit pressure on that part of the element.
ElementVector Quad9ShapeIntegral(
    int dofs_per_node, double hx, double hy, double x0, double x1, double y0, double y1);

}  // namespace combabc::plate
