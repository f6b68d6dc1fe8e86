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
#include "plate/fast_path/section_layout.hpp"

namespace combabc::plate {

class ByteWriter;  // precompute_cache.hpp
class ByteReader;

struct SectionWorkspace;  // Solve's per-thread workspace (section_solve.cpp)

class SectionCondensation {
 public:
  // How the pieces are built and solved.
  struct Settings {
    int group_size = 1;  // sections per group; divides the sections (1: no grouping)
    double frequency_hz = 0.0;
    bool always_pivot = false;
    // The caller has certified that the all-free system is a Higham matrix (real and imaginary
    // parts symmetric positive definite; SensorModel checks it, higham_check.hpp), which makes
    // the unpivoted LDL^T provably stable for every configuration, so Solve skips its residual
    // check (section_solve.cpp).
    bool higham = false;
    // The instruction set of Solve's kernels (vector_kernels.hpp; resolved, and supported by the
    // CPU).
    VectorKernels kernels = VectorKernels::kPortable;
    ThreadPool* pool = nullptr;  // threads for the group pieces (null: this thread)
  };
  // The pieces of `plate` sectioned as `section_layout` says (its loads, one column per load
  // case, and its outputs); they do not depend on the pool.
  SectionCondensation(const Plate& plate,
                      std::shared_ptr<const SectionLayout> section_layout,
                      const Settings& settings);

  // clamps: 2 num_sections bytes (edge A sections, then edge B); w: complex w at every case's
  // outputs, case after case. One factorization of the configuration's system serves all cases.
  void Solve(std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const;

  int num_pieces() const { return static_cast<int>(group_pieces_.size()); }
  bool higham() const { return higham_; }

  // The precompute cache's payload (precompute_cache.hpp; section_condensation_io.cpp): Write
  // stores every member Solve reads but the layout, which is the reader's (the cache's key covers
  // everything it is built from); Read rebuilds the condensation from it, or returns null when
  // the bytes do not describe one consistent with the layout (nothing of it may then be trusted).
  void Write(ByteWriter& w) const;
  static std::unique_ptr<SectionCondensation> Read(
      ByteReader& r, std::shared_ptr<const SectionLayout> section_layout, VectorKernels kernels);
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
                        double frequency_hz,
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

  std::shared_ptr<const SectionLayout> layout_;
  // Construction only (released once the group pieces are built).
  std::vector<Eigen::MatrixXcd> section_condensed_;  // [mesh section * 4 + state] -> its C
  std::vector<Piece> pieces_;
  std::vector<std::array<int, 4>> piece_index_;  // [section][state] -> pieces_ (deduplicated)
  int group_size_ = 0;
  bool always_pivot_ = false;
  bool higham_ = false;  // the caller certified a Higham system: no residual check needed (Solve)
  VectorKernels kernels_ = VectorKernels::kPortable;  // which copy Solve runs
  std::vector<SolvePiece> group_pieces_;
  std::vector<std::vector<int>> group_piece_index_;  // [group][state] -> group_pieces_
  std::vector<OutputLayout> group_layout_;
  // Loads on each cross-section (nc x cases), Jacobi-scaled as the pieces are.
  std::vector<Eigen::MatrixXcd> boundary_load_;
};

}  // namespace combabc::plate
