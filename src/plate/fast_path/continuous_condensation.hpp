#pragma once
// Exact per-call condensation of the sectioned plate when continuous parameters (foundation
// stiffness, a laminate stiffness scale, one loss factor) change every section piece
// (docs/model.md, "Continuous unknowns").
//
// The dynamic stiffness of a call is factor (K_base + mu M_1): K_base is the bending stiffness
// K_real (when one loss factor eta is given: factor = s (1 + i eta)) or K_real + i K_imag (the
// layers' own loss factors: factor = s), M_1 the unit-mass matrix (foundation and inertia), and
// mu = (k_f (1 + i eta_f) - omega^2 rho h) / factor carries the rest. So every condensed section
// piece is a function of the one complex number mu. For each distinct section mesh and each of its
// 4 clamp states the interior I is condensed onto the two end cross-sections B in Craig-Bampton
// form, which is exact:
//   C(mu) = K_G + mu M_G - mu^2 N^T (K_II + mu M_II)^{-1} N,
// with X0 = -K_II^{-1} K_IB, K_G = K_BB + K_BI X0, N = M_II X0 + M_IB, M_G = M_BB + M_BI X0 +
// X0^T N. The resolvent is a power series in mu,
//   (K_II + mu M_II)^{-1} = sum_k (-mu)^k (K_II^{-1} M_II)^k K_II^{-1},
// whose moments T_k = N^T (K_II^{-1} M_II)^k K_II^{-1} N are precomputed. With lambda_1 the
// smallest eigenvalue of (Re K_II, M_II) (Re K_II is positive definite: the interior is held at
// both ends; Im K_II is positive semidefinite: every layer's loss factor is >= 0), the numerical
// range of M^{-1/2} K_II M^{-1/2} keeps |z^H A z| >= lambda_1, so ||(mu K_II^{-1} M_II)^k|| <= q^k
// in the M norm with q = |mu| / lambda_1, and the tail after K terms is at most q^K / (1 - q)
// times the bound on the whole series. A call sums the K terms with q^K <= kSeriesTol (1 - q),
// a truncation far below round-off. Where q > kMaxRatio the series would need more than the
// stored terms, and that state is condensed directly (a sparse LU of K_II + mu M_II per call):
// exact and slower. Loads and output maps inside a section expand the same way.
//
// Several load cases (docs/model.md, "Several load cases"): the section pieces do not depend on
// the loads, so every case shares them and the call's factorization; each distinct section
// carries the output maps of its output sets (OutputSets) and, for each case whose load reaches
// its interior, that case's load and output offsets, and the right-hand sides are one column per
// case.
//
// Per call: evaluate the pieces of the (at most 4 per section mesh) states the configuration
// uses, assemble the block-tridiagonal system on all num_sections + 1 cross-sections, solve it by
// block LDL^T with a residual check (sparse LU fallback) and recover the outputs.
#include <array>
#include <atomic>
#include <complex>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/fast_path/vector_kernels.hpp"
#include "plate/fast_path/section_layout.hpp"

namespace combabc::plate {

struct ContinuousWorkspace;  // Solve's per-thread workspace (continuous_solve.cpp)

class ContinuousCondensation {
 public:
  // Truncation of the series, relative to the bound on its whole sum.
  static constexpr double kSeriesTol = 1e-17;
  // Largest q = |mu| / lambda_1 summed by the series; above it: direct. 0.3 needs 33 stored terms
  // (7 MB at the default mesh) and covers k_f up to ~80 times and s down to ~1/90 of the defaults;
  // 0.5 would need 58 terms for less than twice the range.
  static constexpr double kMaxRatio = 0.3;

  struct Settings {
    bool own_loss_factors = false;  // K_base = K_real + i K_imag (else K_real)
    bool always_pivot = false;      // as SectionCondensation's
    VectorKernels kernels = VectorKernels::kPortable;
  };
  // The precompute of `plate` sectioned as `section_layout` says (its loads and outputs).
  ContinuousCondensation(const Plate& plate,
                         std::shared_ptr<const SectionLayout> section_layout,
                         const Settings& settings);

  // Solves (K_base + mu M_1) u = f for the configuration and every load case's f (one
  // factorization); w: complex w at every case's outputs, case after case (the caller divides by
  // the stiffness factor).
  void Solve(std::span<const std::uint8_t> clamps,
             std::complex<double> mu,
             std::span<std::complex<double>> w) const;

  // Series terms each clamp state uses at mu (the most over the section meshes), or -1 where it is
  // condensed directly.
  std::array<int, 4> SeriesTerms(std::complex<double> mu) const;
  // Terms for q = |mu| / lambda_1, or -1 above kMaxRatio.
  static int TermsFor(double q);
  std::size_t MemoryBytes() const;

 private:
  // The per-call values are all of the form sum_j (-mu)^j V_j, stored as tables whose columns
  // are the V_j (real and imaginary parts apart, so that the real K_base costs one real
  // matrix-matrix product against the powers of -mu). Boundary quantities are Jacobi-scaled.
  //
  // One distinct section mesh in one clamp state: the piece, V_0 = K_G, V_1 = -M_G,
  // V_{k+2} = -T_k, packed (PackPiece: the entries the solve reads).
  struct StateData {
    double lambda_bound = 0.0;  // 0 < lambda_bound <= lambda_1 (infinite without interior)
    Eigen::MatrixXd table_re;
    Eigen::MatrixXd table_im;  // empty when K_base is real
    // For the direct condensation: the split blocks.
    Eigen::SparseMatrix<std::complex<double>> k_ii;
    Eigen::SparseMatrix<std::complex<double>> m_ii;
    Eigen::MatrixXcd k_ib;  // n_I x 2 nc
    Eigen::MatrixXcd m_ib;
    Eigen::MatrixXcd k_bb;
    Eigen::MatrixXcd m_bb;
    std::vector<int> coupled;  // interior dofs coupled to the ends (the non-zero rows of K_IB)
    // Construction only (moved into the table): K_G, M_G, T_k.
    Eigen::MatrixXcd k_static;
    Eigen::MatrixXcd m_static;
    std::vector<Eigen::MatrixXcd> moments;
  };
  // One distinct section (mesh, outputs, interior loads) in one clamp state: rows [output map
  // (n_out x 2 nc by columns, n_out its output sets' rows, OutputLayout); then for each case
  // whose load reaches its interior: load (2 nc), output offsets (its set's rows)];
  // V_0 = [r_B + r_I X0; X0^T f_I; o_0], V_{k+1} = [O_k; g_k; o_{k+1}] with
  // O_k = r_I (K^{-1} M)^k K^{-1} N, g_k = N^T (K^{-1} M)^k K^{-1} f_I, o_k = r_I (...) f_I.
  struct SectionData {
    int map_rows = 0;
    std::vector<int> loaded_cases;           // the cases with an interior load here, ascending
    std::vector<Eigen::Index> loaded_start;  // [loaded case] -> its first row (its load)
    Eigen::MatrixXd table_re;
    Eigen::MatrixXd table_im;
    // For the direct condensation.
    Eigen::MatrixXcd r_i;  // n_out x n_I
    Eigen::MatrixXcd r_b;  // n_out x 2 nc
    Eigen::MatrixXcd f_i;  // n_I x loaded cases
    // [set] -> the interior dofs its outputs read (the non-zero columns of its rows of r_i): per
    // set, so that a set's products have the shape they have in a model of that set alone.
    std::vector<std::vector<int>> read;
    // Construction only, per loaded case where not the maps.
    Eigen::MatrixXcd out_static;
    std::vector<Eigen::MatrixXcd> out_terms;
    std::vector<Eigen::VectorXcd> load_static;
    std::vector<std::vector<Eigen::VectorXcd>> load_terms;
    std::vector<std::vector<Eigen::VectorXcd>> offset_terms;  // o_0 .. o_K (one more)
    // The index of case c in loaded_cases, or -1.
    int LoadedIndex(int c) const {
      for (std::size_t l = 0; l < loaded_cases.size(); ++l) {
        if (loaded_cases[l] == c) return static_cast<int>(l);
      }
      return -1;
    }
  };
  struct Evaluated;  // one call's pieces (continuous_solve.cpp)
  // Solve's body, compiled once per instruction set (kernel_targets.hpp), and the phases of it
  // that read the pieces (continuous_solve.cpp).
  void SolveBody(std::span<const std::uint8_t> clamps,
                 std::complex<double> mu,
                 std::span<std::complex<double>> w) const;
  void EvaluatePieces(std::span<const std::uint8_t> clamps,
                      std::complex<double> mu,
                      ContinuousWorkspace& ws,
                      Evaluated& e) const;
  void Assemble(std::span<const std::uint8_t> clamps,
                const Evaluated& e,
                ContinuousWorkspace& ws) const;
  void RecoverOutputs(const Evaluated& e,
                      ContinuousWorkspace& ws,
                      std::span<std::complex<double>> w) const;
  // Section s's distinct section in clamp state `state`: its index into sections_ (and into an
  // Evaluated's sections).
  std::size_t KindIndex(int s, int state) const {
    return static_cast<std::size_t>(kind_[s]) * 4 + static_cast<std::size_t>(state);
  }
  void SolvePortable(std::span<const std::uint8_t> clamps,
                     std::complex<double> mu,
                     std::span<std::complex<double>> w) const;
  void SolveAvx2(std::span<const std::uint8_t> clamps,
                 std::complex<double> mu,
                 std::span<std::complex<double>> w) const;
  void SolveAvx512(std::span<const std::uint8_t> clamps,
                   std::complex<double> mu,
                   std::span<std::complex<double>> w) const;

  // The series of one (mesh, state) pair and of its sections (docs/model.md, "Continuous
  // unknowns"), in three steps: assemble, prepare each section's outputs and loads, condense.
  void Precompute(const Plate& plate, int mesh_kind, int state);
  // A section's local dofs in one state (SectionLayout::ClassifySectionDofs).
  struct DofClasses {
    std::vector<int> boundary;
    std::vector<int> interior;
    int n_interior = 0;
  };
  struct InteriorTriplets;
  void AssembleState(const Plate& plate,
                     int mesh_kind,
                     int state,
                     const DofClasses& local,
                     InteriorTriplets* triplets);
  void PrepareSection(const Plate& plate, int kind, int state, const DofClasses& local);
  void CondenseInterior(int mesh_kind,
                        int state,
                        const std::vector<int>& kinds,
                        const InteriorTriplets& triplets);
  void EvaluateSeries(
      int mesh_kind, int state, int terms, std::complex<double> mu, Evaluated* e) const;
  void EvaluateDirect(int mesh_kind, int state, std::complex<double> mu, Evaluated* e) const;
  void BuildTables();
  // A symmetric 2 nc x 2 nc piece packed as the solve reads it: the lower triangles of its left
  // and right diagonal blocks by columns (column j of a triangle starts at LowerStart(j)), then
  // its coupling block (rows left, columns right) by columns.
  Eigen::Index PackedSize() const {
    const Eigen::Index nc = layout_->nc();
    return nc * (nc + 1) + nc * nc;
  }
  Eigen::Index LowerStart(int j) const {
    return static_cast<Eigen::Index>(j) * layout_->nc() -
           static_cast<Eigen::Index>(j) * (j - 1) / 2;
  }
  void PackPiece(const Eigen::MatrixXcd& piece, std::complex<double>* out) const;

  std::shared_ptr<const SectionLayout> layout_;
  bool own_loss_factors_;
  bool always_pivot_;
  VectorKernels kernels_;                        // which copy Solve runs
  std::vector<int> mesh_kind_;                   // section -> distinct mesh
  std::vector<int> mesh_section_;                // distinct mesh -> a section that has it
  std::vector<int> kind_;                        // section -> distinct section
  std::vector<int> kind_section_;                // distinct section -> a section that has it
  std::vector<StateData> states_;                // [mesh kind * 4 + state]
  std::vector<SectionData> sections_;            // [kind * 4 + state]
  Eigen::VectorXd boundary_scale_;               // nc: Jacobi scale of every cross-section's dofs
  std::vector<Eigen::MatrixXcd> boundary_load_;  // scaled loads on each cross-section (nc x cases)
};

// SensorModel's continuous precomputes, each built on its first use: [0] K_base = K_real (a loss
// factor given), [1] K_real + i K_imag (the layers' own). When every layer has the same loss
// factor, K_imag = eta K_real and [0] serves both.
struct ContinuousCache {
  std::once_flag once[2];
  std::unique_ptr<ContinuousCondensation> base[2];
  std::atomic<const ContinuousCondensation*> ready[2] = {nullptr, nullptr};
  bool proportional = false;
  double own_loss_factor = 0.0;  // the common loss factor when proportional
};

}  // namespace combabc::plate
