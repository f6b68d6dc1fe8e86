#pragma once
// What every plate element family shares: the plate theory that selects the family, and the
// element matrix types. A family of order p (1: bilinear or cubic Hermite at the 4 corners; 2:
// the 9-node quadratic rectangles of the shear theories, mitc9_element.hpp) has
// `DofsPerNode(theory)` dofs at each of the (p + 1)^2 nodes of a rectangle; local dof
// DofsPerNode (a + (p + 1) b) + k belongs to node (a, b), a, b in {0, ..., p}, at
// (a hx / p, b hy / p) from the element's lower left corner. Dof k = 0 is w, 1 and 2 are the slopes
// along x and y (w_x, w_y in Kirchhoff theory; the rotations phi_x, phi_y of the normal, which
// equal them in the thin limit, in first-order shear deformation theory and the refined zigzag
// theory), so the support masks read alike for every family (plate.hpp, SupportMask); the zigzag
// amplitudes psi_x, psi_y of the refined zigzag theory are dofs 3 and 4.
#include <utility>

#include <Eigen/Dense>

#include "combabc/core/enum_names.hpp"

namespace combabc::plate {

enum class PlateTheory {
  // Kirchhoff (classical laminated plate theory): no transverse shear; Bogner-Fox-Schmit
  // elements (bfs_element.hpp), dofs (w, w_x, w_y, w_xy).
  kKirchhoff,
  // First-order shear deformation (Reissner-Mindlin) with an energy-consistent shear stiffness of
  // the laminate (laminate.hpp); MITC4 elements (mitc4_element.hpp) or,
  // at element order 2, MITC9 (mitc9_element.hpp); dofs (w, phi_x, phi_y).
  kFsdt,
  // Refined zigzag theory (Tessler, Di Sciuva & Gherlone 2009/2010), a layer-wise theory for
  // sandwiches with a soft core: the in-plane displacements add a piecewise-linear zigzag
  // function of the layers' shear moduli times amplitudes psi (laminate.hpp); RZT4 elements
  // (rzt_element.hpp) or RZT9 at element order 2 (mitc9_element.hpp), dofs (w, theta_x, theta_y,
  // psi_x, psi_y).
  kRzt,
};

inline constexpr int kMaxDofsPerNode = 5;
inline constexpr int kMaxElementNodes = 9;  // the quadratic rectangle
inline constexpr int kMaxElementDofs = kMaxElementNodes * kMaxDofsPerNode;

constexpr int DofsPerNode(PlateTheory theory) {
  switch (theory) {
    case PlateTheory::kKirchhoff:
      return 4;
    case PlateTheory::kFsdt:
      return 3;
    case PlateTheory::kRzt:
      return 5;
  }
  return 4;
}

// Sized per family at run time, stored inline (no heap) up to the largest family.
using ElementMatrix = Eigen::Matrix<double,
                                    Eigen::Dynamic,
                                    Eigen::Dynamic,
                                    Eigen::ColMajor,
                                    kMaxElementDofs,
                                    kMaxElementDofs>;
using ElementVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxElementDofs, 1>;

// The three real matrices from which every complex dynamic stiffness is combined:
//   K_dyn = stiffness_real + i stiffness_imag + (k_f (1 + i eta_f) - omega^2 rho h) mass_unit.
// mass_unit acts on w only (translational inertia of unit mass per area, which the foundation
// shares). rotary_inertia is the consistent mass of the rotations (and zigzag amplitudes) of the
// shear-deformable theories, zero for Kirchhoff; it enters the modal mass
// rho h mass_unit + rotary_inertia, and not the harmonic solve (nor its fast paths): at the
// sensor's 5 Hz it would move the profile by about 2e-5 of its peak (docs/model.md, "Natural
// frequencies of thick plates").
struct ElementMatrices {
  ElementMatrix stiffness_real;
  ElementMatrix stiffness_imag;
  ElementMatrix mass_unit;
  ElementMatrix rotary_inertia;  // kg: already multiplied by the section's inertia
};

}  // namespace combabc::plate

namespace combabc {

template <>
struct EnumNames<plate::PlateTheory> {
  static constexpr std::pair<plate::PlateTheory, const char*> kNames[] = {
      {plate::PlateTheory::kKirchhoff, "kirchhoff"},
      {plate::PlateTheory::kFsdt, "fsdt"},
      {plate::PlateTheory::kRzt, "rzt"},
  };
};

}  // namespace combabc
