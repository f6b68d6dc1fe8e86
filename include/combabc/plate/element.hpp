#pragma once
// What every plate element family shares: the plate theory that selects the family, and the
// element matrix types. A family has `DofsPerNode(theory)` dofs at each of the 4 corners of a
// rectangle; local dof DofsPerNode (a + 2 b) + k belongs to corner (a, b), a, b in {0, 1}, at
// (a hx, b hy) from the element's lower left corner. Dof k = 0 is w, 1 and 2 are the slopes
// along x and y (w_x, w_y in Kirchhoff theory; the rotations phi_x, phi_y of the normal, which
// equal them in the thin limit, in first-order shear deformation theory), so the support masks
// read the same for every family (plate.hpp, SupportMask).
#include <utility>

#include <Eigen/Dense>

#include "combabc/core/enum_names.hpp"

namespace combabc::plate {

enum class PlateTheory {
  // Kirchhoff (classical laminated plate theory): no transverse shear; Bogner-Fox-Schmit
  // elements (bfs_element.hpp), dofs (w, w_x, w_y, w_xy).
  kKirchhoff,
  // First-order shear deformation (Reissner-Mindlin) with an energy-consistent shear stiffness of
  // the laminate (laminate.hpp); MITC4 elements (mitc4_element.hpp), dofs (w, phi_x, phi_y).
  kFsdt,
};

inline constexpr int kMaxDofsPerNode = 4;
inline constexpr int kMaxElementDofs = 4 * kMaxDofsPerNode;

constexpr int DofsPerNode(PlateTheory theory) { return theory == PlateTheory::kFsdt ? 3 : 4; }

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
// mass_unit acts on w only (translational inertia of unit mass per area; rotary inertia is
// neglected in every theory, docs/model.md).
struct ElementMatrices {
  ElementMatrix stiffness_real;
  ElementMatrix stiffness_imag;
  ElementMatrix mass_unit;
};

}  // namespace combabc::plate

namespace combabc {

template <>
struct EnumNames<plate::PlateTheory> {
  static constexpr std::pair<plate::PlateTheory, const char*> kNames[] = {
      {plate::PlateTheory::kKirchhoff, "kirchhoff"},
      {plate::PlateTheory::kFsdt, "fsdt"},
  };
};

}  // namespace combabc
