#pragma once
// A rectangular plate on a structured grid of rectangular elements of one family (element.hpp:
// Kirchhoff theory on Bogner-Fox-Schmit elements, or first-order shear deformation theory on MITC4
// or MITC9 elements, or the refined zigzag theory on RZT4 or RZT9 elements), with
// per-edge-segment supports, an optional Winkler foundation, point or patch loads, and static,
// harmonic and modal solves. The sensor simulator (sensor_model.hpp) is built on this; the
// validation tests use it directly.
//
// Element order (Plate's element_order): 1, every grid interval is an element (BFS, MITC4,
// RZT4); 2 (shear theories only), each element spans 2 x 2 grid intervals with the 9-node
// quadratic rectangles of mitc9_element.hpp, so the grid lists the mid-side nodes too and
// element (ex, ey) has its corners at grid nodes (2 ex, 2 ey) and (2 ex + 2, 2 ey + 2).
//
// Degrees of freedom: node (i, j) at (grid.x[i], grid.y[j]) has index i (ny + 1) + j and dofs
// n node + k with n = dofs_per_node(): k = 0 w, 1 w_x, 2 w_y, 3 w_xy for Kirchhoff; k = 0 w,
// 1 phi_x, 2 phi_y for FSDT; k = 0 w, 1 theta_x, 2 theta_y, 3 psi_x, 4 psi_y for RZT
// (cross-section-major, so the dofs of one cross-section x = grid.x[i]
// are contiguous, which the section condensation relies on).
#include <complex>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>
#include "combabc/core/enum_names.hpp"
#include "combabc/core/error.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "combabc/plate/elements/element.hpp"
#include "combabc/plate/elements/laminate.hpp"

namespace combabc::plate {

// Thrown by a solve whose system is singular or too close to it to be trusted: a clamp
// configuration that leaves the plate free to move as a rigid body (no foundation, no fixed edge
// and frequency 0), or an undamped resonance. It is a property of the configuration, so a
// calibration counts that candidate as a failed simulation with this reason (docs/model.md,
// "Singular configurations"); `combabc simulate` reports it as a config error.
class SingularSystem : public Error {
 public:
  explicit SingularSystem(double amplification);
  double amplification() const { return amplification_; }

 private:
  double amplification_;
};

// The fast paths' test (block_ldlt.hpp; their unknowns are the condensed cross-sections): a
// solution (in Jacobi-scaled units, where the system's entries are at most about 2) more than
// this many times larger than its load proves a condition number above it: SingularSystem. A
// rigid-body motion left free gives 8e9 to 1e14 on the meshes and theories of the tests; the
// weakest support that holds, one 5 cm clamp under a static load, at most 7e5.
inline constexpr double kMaxAmplification = 1e8;

// The full sparse solve's test (Plate::SolveHarmonic): a residual, after iterative refinement,
// above this fraction of the load (largest Jacobi-scaled entries) is SingularSystem. A singular
// system's load has a part that no solution reaches (the resultant, against a free rigid-body
// motion), which stays in the residual: 1e-2 to 5e-1 of the load on 10 x 6 to 40 x 24 elements
// per section, Kirchhoff and RZT. A regular system reaches round-off times its amplification,
// which that full system's mesh drives, unlike the condensed one's: Kirchhoff's graded width
// (an 11.6 um edge element at 24 across) takes the scaled system with every clamp free to a
// condition number about 1e13, its solution to 2e8 to 8e8 times the load and its residual to
// 3e-7 at 40 x 24 (docs/model.md, "Singular configurations").
inline constexpr double kMaxResidual = 1e-4;

enum class Support {
  kFree,             // no constraint
  kSimplySupported,  // w = 0 and the tangential slope = 0 along the edge
  kClamped,          // w = 0 and both slopes = 0 (so all four BFS dofs vanish on the edge; in
                     // FSDT w and both rotations of the normal, a "hard" clamp that holds the
                     // whole edge face, as a clamp gripping the strip over its thickness does;
                     // in RZT also both zigzag amplitudes, for the same reason)
};
}  // namespace combabc::plate

namespace combabc {

template <>
struct EnumNames<plate::Support> {
  static constexpr std::pair<plate::Support, const char*> kNames[] = {
      {plate::Support::kFree, "free"},
      {plate::Support::kSimplySupported, "simply_supported"},
      {plate::Support::kClamped, "clamped"},
  };
};

}  // namespace combabc

namespace combabc::plate {

enum class Edge {
  kBottom,  // y = 0   (the sensor's edge A, clamps 1..18)
  kTop,     // y = W   (edge B, clamps 19..36)
  kLeft,    // x = 0
  kRight,   // x = L
};

// Node coordinates, strictly increasing, in metres; grid.x.front() = grid.y.front() = 0.
struct Grid {
  std::vector<double> x;
  std::vector<double> y;
  // Node intervals (the elements at element order 1).
  int nx() const { return static_cast<int>(x.size()) - 1; }
  int ny() const { return static_cast<int>(y.size()) - 1; }
};
Grid UniformGrid(double length, double width, int nx, int ny);

// Which dofs are fixed: one bit mask per node (bit k fixes dof k of dofs_per_node).
class Constraints {
 public:
  explicit Constraints(const Grid& grid, PlateTheory theory = PlateTheory::kKirchhoff);

  // Supports the nodes of `edge` whose coordinate along the edge lies in the closed interval
  // [from, to] (a tolerance of 1e-9 of the edge length). Masks are OR-ed, so a node shared by a
  // clamped and a free segment is clamped, and a corner gets the union of both edges.
  void AddEdgeSupport(Edge edge, double from, double to, Support support);
  void AddEdgeSupport(Edge edge, Support support);
  void FixNode(int node, std::uint8_t mask) { masks_[node] |= mask & all_dofs_; }

  std::uint8_t mask(int node) const { return masks_[node]; }
  int dofs_per_node() const { return dofs_per_node_; }
  bool IsFixed(int dof) const {
    return ((masks_[dof / dofs_per_node_] >> (dof % dofs_per_node_)) & 1) != 0;
  }
  int num_fixed() const;

 private:
  std::vector<double> x_;
  std::vector<double> y_;
  PlateTheory theory_;
  int dofs_per_node_;
  std::uint8_t all_dofs_;  // the mask of every dof of a node
  std::vector<std::uint8_t> masks_;
};

// Mask of the dofs fixed by `support` on a node of `edge` (see Support) in `theory`'s dof layout:
// dofs 0-2 mean (w, slope along x, slope along y) in each family. Clamped fixes every dof of
// the node (in RZT also the zigzag amplitudes: a clamp gripping the whole thickness stops the
// zigzag of the in-plane displacements as well). Simply supported is the "hard" support in FSDT
// and RZT: w and the rotation about the edge's normal (the tangential slope) are fixed, and in
// RZT the tangential zigzag amplitude, which the Navier solution of the theory also has.
std::uint8_t SupportMask(Edge edge, Support support, PlateTheory theory);

// A transverse force of amplitude `force` (N) at (x, y): a point load when patch_length and
// patch_width are 0, else a uniform pressure on the patch_length x patch_width rectangle centred
// there (clipped to the plate).
struct Load {
  double x = 0.0;
  double y = 0.0;
  double force = 1.0;
  double patch_length = 0.0;
  double patch_width = 0.0;
};

struct Modes {
  std::vector<double> frequencies_hz;  // ascending
  Eigen::MatrixXd shapes;              // num_dofs x count, mass-normalised, zero on fixed dofs
};

class Plate {
 public:
  // foundation_stiffness: Winkler modulus k_f (N/m^3) acting on the whole plate, with loss factor
  // eta_f (reaction k_f (1 + i eta_f) w). element_order 2 needs a shear theory, an even number
  // of grid intervals along both axes and each odd node at the midpoint of its element (throws
  // combabc::Error otherwise).
  Plate(Grid grid,
        PlateSection section,
        double foundation_stiffness = 0.0,
        double foundation_loss_factor = 0.0,
        PlateTheory theory = PlateTheory::kKirchhoff,
        int element_order = 1);

  const Grid& grid() const { return grid_; }
  PlateTheory theory() const { return theory_; }
  int dofs_per_node() const { return DofsPerNode(theory_); }
  int element_order() const { return order_; }
  int element_dofs() const { return (order_ + 1) * (order_ + 1) * DofsPerNode(theory_); }
  // Elements along x and y.
  int num_elements_x() const { return grid_.nx() / order_; }
  int num_elements_y() const { return grid_.ny() / order_; }
  // An empty constraint set of this plate's dof layout.
  Constraints NewConstraints() const { return Constraints(grid_, theory_); }
  const PlateSection& section() const { return section_; }
  double foundation_stiffness() const { return foundation_stiffness_; }
  double foundation_loss_factor() const { return foundation_loss_factor_; }
  int num_nodes() const { return (grid_.nx() + 1) * (grid_.ny() + 1); }
  int num_dofs() const { return dofs_per_node() * num_nodes(); }
  int Node(int i, int j) const { return i * (grid_.ny() + 1) + j; }
  // Global dof of local dof `local` of element (ex, ey).
  int ElementDof(int ex, int ey, int local) const;
  const ElementMatrices& Element(int ex, int ey) const {
    return unique_elements_[element_kind_[ex * num_elements_y() + ey]];
  }

  // Coefficient of mass_unit in the dynamic stiffness at `frequency_hz`:
  // k_f (1 + i eta_f) - omega^2 rho h.
  std::complex<double> MassCoefficient(double frequency_hz) const;

  // Consistent load vector (num_dofs).
  Eigen::VectorXd LoadVector(const Load& load) const;

  // Dynamic stiffness K (1 + i eta) + k_f (1 + i eta_f) M_1 - omega^2 rho h M_1 restricted to the
  // free dofs; free_dofs receives their global indices in order.
  Eigen::SparseMatrix<std::complex<double>> DynamicStiffness(const Constraints& constraints,
                                                             double frequency_hz,
                                                             std::vector<int>* free_dofs) const;

  // Static solve with the real stiffness (+ real foundation); throws if the plate is not
  // supported. Returns all num_dofs (zero on fixed dofs).
  Eigen::VectorXd SolveStatic(const Constraints& constraints, const Load& load) const;
  // Harmonic solve of (K(1 + i eta) + k_f(1 + i eta_f)M_1 - omega^2 M) u = f by sparse LU (the
  // matrix is complex symmetric, not Hermitian, so no Cholesky/LDL^H).
  Eigen::VectorXcd SolveHarmonic(const Constraints& constraints,
                                 const Load& load,
                                 double frequency_hz) const;
  Eigen::VectorXcd SolveHarmonic(const Constraints& constraints,
                                 const Eigen::VectorXd& load_vector,
                                 double frequency_hz) const;

  // Undamped natural frequencies (real parts of the stiffnesses; mass rho h M_1 plus the rotary
  // inertia of FSDT and RZT, element.hpp) and mass-normalised mode shapes by shift-invert subspace
  // iteration; `count` lowest.
  Modes ComputeModes(const Constraints& constraints, int count) const;

  // Deflection w at (x, y) interpolated with the element shape functions.
  double Deflection(const Eigen::VectorXd& u, double x, double y) const;
  std::complex<double> Deflection(const Eigen::VectorXcd& u, double x, double y) const;
  // Interpolation row: w(x, y) = row . u over the returned element_dofs() global dofs (dofs must
  // hold kMaxElementDofs).
  void InterpolationRow(double x, double y, int dofs[kMaxElementDofs], ElementVector* row) const;

 private:
  Grid grid_;
  PlateSection section_;
  double foundation_stiffness_;
  double foundation_loss_factor_;
  PlateTheory theory_;
  int order_;
  std::vector<ElementMatrices> unique_elements_;  // one per distinct (hx, hy)
  std::vector<int> element_kind_;  // ex * num_elements_y() + ey -> index into unique_elements_
};

}  // namespace combabc::plate
