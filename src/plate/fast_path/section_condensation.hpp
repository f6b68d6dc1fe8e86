#pragma once
// Exact fast re-analysis of a plate whose only varying boundary conditions are switchable edge
// sections (docs/model.md, "Section condensation").
//
// The mesh has node lines on the section boundaries x_0 < ... < x_S. For each section s and each
// of its 4 clamp states (edge A fixed?, edge B fixed?) the section's interior dofs (nodes strictly
// between x_s and x_{s+1}, less those fixed by the state) are condensed, by a sparse LU, onto the
// dofs of its two end cross-sections, which are all kept:
//   C = S_BB - S_BI S_II^{-1} S_IB,  g = -S_BI S_II^{-1} f_I,
// together with the map from the end cross-sections to the outputs inside the section,
//   w_out = r_I S_II^{-1} f_I + (r_B - r_I S_II^{-1} S_IB) u_B.
// Pieces of `group_size` consecutive sections are then composed, for each of their 4^group_size
// states, by eliminating the cross-sections inside the group (dense Schur complements of the
// section pieces), so a configuration's system has num_sections / group_size + 1 block rows.
// The plate's two end cross-sections are folded into the first and last groups (their
// constraints depend only on those groups' states and the short edges), leaving the
// num_sections / group_size - 1 inner group boundaries as unknowns.
// A configuration then assembles the block-tridiagonal system on the S + 1 cross-sections from the
// cached pieces, removes the cross-section dofs that either adjoining section fixes (and those of
// the short edges), solves it by block elimination and recovers the outputs. Every step is exact
// algebra on the same discrete system as the full solve.
//
// Several load cases (docs/model.md, "Several load cases") share the clamps, the mesh and the
// frequency, so they share the system matrix: the loads are the columns of one load matrix, the
// condensed loads g (and the pieces' loads after composition) have one column per case, and a
// configuration is factorized once and solved for every column. C depends only on a section's
// mesh and clamp state, so it is condensed once per mesh and state (sections whose elements are
// the same element matrices) whatever loads or outputs the sections have. Each case has its own
// outputs (positions and line); cases with equal outputs share one output set, whose maps are
// condensed once, while each case keeps its own output offsets r_I S_II^{-1} f_I (its own load).
#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Dense>

#include "combabc/core/thread_pool.hpp"
#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/fast_path/vector_kernels.hpp"

namespace combabc::plate {

class ByteWriter;  // precompute_cache.hpp
class ByteReader;

// The masks that fix a cross-section's dofs (bit k of a mask: the node's dof k is fixed): an
// edge node of a fixed clamp (edge A at j = 0, edge B at j = ny) and the plate's two end
// cross-sections.
struct CrossSectionMasks {
  std::uint8_t fixed_a, fixed_b, start, end;
};
// The free dofs (0..nc-1, in order) of cross-section `cross_section` of `num_sections` sections
// whose edge-A / edge-B clamps are fixed as given; shared by both condensations.
inline void CrossSectionFreeDofs(int nc,
                                 int ny,
                                 int num_sections,
                                 const CrossSectionMasks& masks,
                                 int cross_section,
                                 bool fixed_a,
                                 bool fixed_b,
                                 std::vector<int>* free) {
  free->clear();
  const int dofs_per_node = nc / (ny + 1);
  for (int d = 0; d < nc; ++d) {
    const int j = d / dofs_per_node;
    const int bit = 1 << (d % dofs_per_node);
    int mask = 0;
    if (fixed_a && j == 0) mask |= masks.fixed_a;
    if (fixed_b && j == ny) mask |= masks.fixed_b;
    if (cross_section == 0) mask |= masks.start;
    if (cross_section == num_sections) mask |= masks.end;
    if ((mask & bit) == 0) free->push_back(d);
  }
}

// The local dofs of one clamp section of m grid intervals ((m + 1) cross-sections of nc dofs;
// m = 2 x its elements at element order 2, whose mid-side node lines are cross-sections too):
// boundary[d] indexes [left; right] for the first and last cross-sections, interior[d] indexes
// the section's interior unknowns, -1 otherwise (a dof fixed by a clamp); returns the interior
// count. `state` bit 0 / bit 1: the edge-A / edge-B clamp is fixed. Shared by both condensations.
inline int ClassifySectionDofs(int m,
                               int nc,
                               int ny,
                               int state,
                               std::uint8_t fixed_mask_a,
                               std::uint8_t fixed_mask_b,
                               std::vector<int>* boundary,
                               std::vector<int>* interior) {
  const int n_local = (m + 1) * nc;
  const bool fixed_a = (state & 1) != 0;
  const bool fixed_b = (state & 2) != 0;
  const int dofs_per_node = nc / (ny + 1);
  boundary->assign(n_local, -1);
  interior->assign(n_local, -1);
  int n_interior = 0;
  for (int d = 0; d < n_local; ++d) {
    if (d < nc) {
      (*boundary)[d] = d;
    } else if (d >= m * nc) {
      (*boundary)[d] = d - (m - 1) * nc;
    } else {
      const int j = (d / dofs_per_node) % (ny + 1);
      const int bit = 1 << (d % dofs_per_node);
      const bool fixed = (fixed_a && j == 0 && (fixed_mask_a & bit)) ||
                         (fixed_b && j == ny && (fixed_mask_b & bit));
      if (!fixed) (*interior)[d] = n_interior++;
    }
  }
  return n_interior;
}

// One load case's outputs: w along the line y (m) at the positions x (m).
struct CaseOutputs {
  std::vector<double> x;
  double y = 0.0;
};

// The load cases' outputs grouped into output sets: cases with the same positions and line share
// one set, whose output maps both condensations condense once. The outputs of case c are
// w[first_output[c] + k] for its positions k (SensorOptions::OutputOffset).
struct OutputSets {
  std::vector<int> set_of_case;  // case -> its set
  std::vector<int> case_of_set;  // set -> the first case with it (its positions, line)
  std::vector<std::vector<int>> cases_of_set;  // set -> its cases, ascending
  std::vector<std::size_t> first_output;       // case -> its first output; [num cases] = the total
  OutputSets() = default;                      // empty; filled by SectionCondensation::Read
  explicit OutputSets(const std::vector<CaseOutputs>& outputs);
  int num_sets() const { return static_cast<int>(case_of_set.size()); }
  int num_cases() const { return static_cast<int>(set_of_case.size()); }
};

// Where the outputs of a section (or a group of sections) sit in its pieces: the output-map rows
// set after set, the output offsets case after case (each case has its set's rows, in the same
// order). Shared by both condensations.
struct OutputLayout {
  std::vector<std::vector<int>> positions;  // [set] -> its positions here (indices), ascending
  std::vector<int> map_begin;               // [set] -> its first map row; [num sets] = the rows
  std::vector<int> offset_begin;            // [case] -> its first offset; [num cases] = the total
  // Fills map_begin and offset_begin from positions.
  void Finish(const OutputSets& sets);
  int map_rows() const { return map_begin.back(); }
  int offset_rows() const { return offset_begin.back(); }
  int rows_of_case(const OutputSets& sets, int c) const {
    return static_cast<int>(positions[sets.set_of_case[c]].size());
  }
};

// The outputs' sections: layouts[s] for each of num_sections sections of `intervals` grid
// intervals (each output belongs to the section of the element that holds it: an output on a
// section boundary depends only on that cross-section's dofs, so either neighbour is exact), and
// relative_x[s][set] their positions relative to the section's start. Shared by both
// condensations.
void AssignOutputs(const Plate& plate,
                   int num_sections,
                   int intervals,
                   const std::vector<CaseOutputs>& outputs,
                   const OutputSets& sets,
                   std::vector<OutputLayout>* layouts,
                   std::vector<std::vector<std::vector<double>>>* relative_x);

struct SectionWorkspace;  // Solve's per-thread workspace (section_solve.cpp)

class SectionCondensation {
 public:
  // `plate` must have num_sections * elements_per_section elements along x (any element order).
  // Masks: dofs fixed on
  // an edge-A / edge-B node by a fixed section, and on every node of the first / last
  // cross-section by the short edges.
  // group_size must divide num_sections (1 disables grouping). `loads`: one column per load case
  // (the plate's load vectors); `outputs`: each case's outputs. `higham`: the caller has certified
  // that the all-free system is a Higham matrix (real and imaginary parts symmetric positive
  // definite; SensorModel checks it), which makes the unpivoted LDL^T provably stable for every
  // configuration, so Solve skips its residual check (section_solve.cpp). `kernels`: the
  // instruction set of Solve's kernels (vector_kernels.hpp; resolved, and supported by the CPU).
  // `pool`: threads for the group pieces (null: this thread); the pieces do not depend on it.
  SectionCondensation(const Plate& plate,
                      int num_sections,
                      int elements_per_section,
                      int group_size,
                      std::uint8_t fixed_mask_a,
                      std::uint8_t fixed_mask_b,
                      std::uint8_t start_mask,
                      std::uint8_t end_mask,
                      const Eigen::MatrixXd& loads,
                      double frequency_hz,
                      const std::vector<CaseOutputs>& outputs,
                      bool always_pivot = false,
                      bool higham = false,
                      VectorKernels kernels = VectorKernels::kPortable,
                      ThreadPool* pool = nullptr);

  // clamps: 2 num_sections bytes (edge A sections, then edge B); w: complex w at every case's
  // outputs, case after case. One factorization of the configuration's system serves all cases.
  void Solve(std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const;

  int num_pieces() const { return static_cast<int>(group_pieces_.size()); }
  bool higham() const { return higham_; }

  // The precompute cache's payload (precompute_cache.hpp; section_condensation_io.cpp): Write
  // stores every member Solve reads; Read rebuilds the condensation from it, or returns null when
  // the bytes do not describe a consistent one (nothing of it may then be trusted).
  void Write(ByteWriter& w) const;
  static std::unique_ptr<SectionCondensation> Read(ByteReader& r, VectorKernels kernels);
  std::size_t MemoryBytes() const;

 private:
  SectionCondensation() = default;  // for Read
  bool Consistent() const;          // Read's check of a payload's sizes and indices
  // A section piece: its condensed matrix C (index in section_condensed_, which the sections of
  // one mesh share in each clamp state), its loads and outputs.
  struct Piece {
    int condensed = -1;
    Eigen::MatrixXcd load;           // [left; right] x load cases
    Eigen::MatrixXcd output_map;     // output-set rows (OutputLayout) x [left; right]
    Eigen::VectorXcd output_offset;  // each case's outputs (OutputLayout)
  };
  // A complex matrix as two real ones (block_ldlt.hpp's split storage), column-major.
  struct SplitMatrix {
    Eigen::MatrixXd re;
    Eigen::MatrixXd im;
    SplitMatrix() = default;
    explicit SplitMatrix(const Eigen::MatrixXcd& a) : re(a.real()), im(a.imag()) {}
    std::size_t Bytes() const { return sizeof(double) * static_cast<std::size_t>(re.size() * 2); }
  };
  // What the per-configuration solve reads of a group piece, in split storage so that its loops
  // need no shuffles and a contiguous run of free dofs is a contiguous run of memory.
  struct SolvePiece {
    SplitMatrix left_block;   // diagonal block of the kept left end (nc x nc); empty when folded in
    SplitMatrix right_block;  // likewise for the right end
    // Pieces with both ends kept: the coupling block condensed(left, right) = coupling_left *
    // coupling_right^T (nc x rank each), from a rank-revealing QR less the round-off-level rest.
    SplitMatrix coupling_left;
    SplitMatrix coupling_right;
    Eigen::MatrixXcd load;           // [left; right] kept dofs x load cases
    SplitMatrix output_map;          // output-set rows in the group x [left; right] kept dofs
    Eigen::VectorXcd output_offset;  // each case's outputs in the group (group_layout_)
    int left_size = 0;
    int right_size = 0;
    // A group with no kept end (the whole plate in one group) is solved in FinishGroup, not in
    // Solve: the amplification of that solve when above kMaxAmplification (singular), else 0;
    // Solve throws SingularSystem for it.
    double singular = 0.0;
  };
  // The pieces of the distinct sections (`representatives`, their first sections) in one clamp
  // state: C once per mesh, then each section's loads and output maps (section_condensation.cpp).
  void CondenseSections(const Plate& plate,
                        int state,
                        const Eigen::MatrixXd& loads,
                        double frequency_hz,
                        const std::vector<CaseOutputs>& outputs,
                        const std::vector<int>& representatives);
  const Eigen::MatrixXcd& Condensed(const Piece& piece) const {
    return section_condensed_[piece.condensed];
  }
  // A group's inner cross-sections eliminated in one clamp state: what depends only on the
  // condensed matrices of its sections, shared by the groups made of the same ones.
  struct GroupElimination {
    int left_size = 0;
    int right_size = 0;
    std::vector<int> boundary_index;  // group dof -> [left; right] kept dof, or -1
    std::vector<int> interior_index;  // group dof -> inner free dof, or -1
    std::vector<int> interior_cross_sections;
    Eigen::MatrixXcd k_bi;                     // kept x inner
    Eigen::VectorXd scale;                     // Jacobi scale of the inner block
    Eigen::PartialPivLU<Eigen::MatrixXcd> lu;  // of the scaled inner block
    Eigen::MatrixXcd x_b;                      // inner x kept: K_II^-1 K_IB
    SolvePiece blocks;  // the kept ends' blocks and coupling as Solve reads them (scaled)
  };
  // `scale`: the cross-section Jacobi scale that Solve's pieces carry.
  GroupElimination EliminateGroup(int group, int state, const Eigen::VectorXd& scale) const;
  // The group's own piece: its loads and outputs through the shared elimination.
  SolvePiece FinishGroup(const GroupElimination& e,
                         int group,
                         int state,
                         const Eigen::VectorXd& scale) const;
  // Solve's body, compiled once per instruction set (SolvePortable, SolveAvx2, SolveAvx512), and
  // the phases of it that read the pieces (section_solve.cpp).
  void SolveBody(std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const;
  void SolvePortable(std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const;
  void SolveAvx2(std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const;
  void SolveAvx512(std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const;
  void Assemble(std::span<const std::uint8_t> clamps, bool in_place, SectionWorkspace& ws) const;
  void AssembleDiagonal(std::span<const std::uint8_t> clamps,
                        int row,
                        const SectionWorkspace& ws,
                        double* ar,
                        double* ai,
                        std::ptrdiff_t ld) const;
  void FallBack(std::span<const std::uint8_t> clamps, bool in_place, SectionWorkspace& ws) const;
  void RecoverGroupOutputs(std::span<const std::uint8_t> clamps,
                           int group,
                           SectionWorkspace& ws,
                           std::span<std::complex<double>> w) const;
  const SolvePiece& GroupPieceOf(int group, std::span<const std::uint8_t> clamps) const;
  // Free dofs (0..nc-1) of a cross-section between sections with edge-A / edge-B flags.
  void FreeDofs(int cross_section, bool fixed_a, bool fixed_b, std::vector<int>* free) const {
    CrossSectionFreeDofs(nc_,
                         ny_,
                         num_sections_,
                         {fixed_mask_a_, fixed_mask_b_, start_mask_, end_mask_},
                         cross_section,
                         fixed_a,
                         fixed_b,
                         free);
  }

  int num_sections_ = 0;
  int intervals_per_section_ = 0;  // grid intervals: elements_per_section x the element order
  int ny_ = 0;
  int nc_ = 0;  // dofs per cross-section, dofs_per_node (ny + 1) over the grid's ny
  std::uint8_t fixed_mask_a_ = 0;
  std::uint8_t fixed_mask_b_ = 0;
  std::uint8_t start_mask_ = 0;
  std::uint8_t end_mask_ = 0;
  int num_cases_ = 0;
  OutputSets sets_;
  // Construction only (released once the group pieces are built).
  std::vector<int> mesh_of_section_;  // section -> the first section with the same element matrices
  std::vector<Eigen::MatrixXcd> section_condensed_;  // [mesh section * 4 + state] -> its C
  std::vector<Piece> pieces_;
  std::vector<std::array<int, 4>> piece_index_;  // [section][state] -> pieces_ (deduplicated)
  std::vector<OutputLayout> section_layout_;
  int group_size_ = 0;
  bool always_pivot_ = false;
  bool higham_ = false;  // the caller certified a Higham system: no residual check needed (Solve)
  VectorKernels kernels_ = VectorKernels::kPortable;  // which copy Solve runs
  std::vector<SolvePiece> group_pieces_;
  std::vector<std::vector<int>> group_piece_index_;  // [group][state] -> group_pieces_
  std::vector<OutputLayout> group_layout_;
  std::vector<Eigen::MatrixXcd> boundary_load_;  // loads on each cross-section (nc x cases)
  // [cross-section][edge A fixed | edge B fixed << 1] -> its free dofs (FreeDofs), for Solve.
  std::vector<std::array<std::vector<int>, 4>> free_dofs_;
};

}  // namespace combabc::plate
