// The per-configuration solve of the condensed system (docs/model.md, "Section condensation").
// The cached pieces are already Jacobi-scaled (SectionCondensation's constructor), so the
// unknowns here are scaled cross-section dofs and the output maps take them as they are.
//
// The unknowns are the free dofs of the inner group boundaries; the matrix is block tridiagonal
// and complex symmetric (K(1 + i eta) - omega^2 M is symmetric, not Hermitian). It is solved by
// block elimination with an unpivoted complex-symmetric LDL^T of each pivot block (about half the
// work of LU, and symmetric Schur complements). A dense partial-pivoting LU of the whole condensed
// system is the fallback when a pivot breaks down.
//
// Several load cases (docs/model.md, "Several load cases") share the matrix: their right-hand
// sides are carried as extra rows through the one factorization, each then back-substituted,
// checked (residual, amplification) and recovered on its own. A case's column sees exactly the
// operations a single case's did, so one case gives the bits it gave before there were several.
//
// When is the unpivoted path safe? For a Higham matrix A = B + iC, B and C real symmetric
// positive definite, Gaussian elimination without pivoting has growth factor below 3 (Higham,
// Math. Comp. 67, 1998; below 2 by Drury 2013) and so is backward stable; principal submatrices
// (fixed dofs), Schur complements (condensation, block elimination) and real diagonal scalings
// (Jacobi) of a Higham matrix are Higham matrices. SensorModel certifies it once for the all-free
// system (the default: the real part is positive definite at 5 Hz, below every resonance, and
// the loss makes the imaginary part positive definite); every configuration's condensed system is
// then one too, and only the pivots and the finiteness of the result are checked. Without the
// certificate (above a resonance, no loss on some stiffness) every solve is followed by a
// residual check of the assembled system, which must pass or the fallback runs.
//
// Performance (docs/benchmarks.md, docs/model.md "Performance"): the coupling between
// neighbouring rows is a group's end-to-end block, numerically of low rank (SectionCondensation's
// constructor factors it as P Q^T), so a Schur complement costs O(n^2 r) rather than O(n^3); the
// triangular solves with P and the right-hand sides ride along inside the factorization. All the
// per-configuration algebra runs on split real/imaginary arrays (block_ldlt.hpp) in plain loops
// that the compiler vectorizes, two axpys per pass; the workspace is per thread and reused.
//
// SolveBody runs the phases in order: assemble the rows from the configuration's group pieces
// (Assemble), eliminate (EliminateRows), back-substitute (BackSubstitute), certify or check the
// results (FlagNonFiniteResults for a certified system, FlagLargeRowResiduals otherwise), fall
// back for the cases that need it (FallBack), refuse a singular system (ThrowIfSingular) and
// recover the outputs (RecoverGroupOutputs).
#include <algorithm>
#include <cmath>
#include <vector>

#include "combabc/core/check.hpp"
#include "plate/fast_path/block_ldlt.hpp"
#include "plate/fast_path/section_condensation.hpp"

namespace combabc::plate {

// Solve's per-thread workspace: the block rows (BlockWorkspace) and the couplings between them in
// factored form.
struct SectionWorkspace : BlockWorkspace {
  // Coupling U_i between rows i and i + 1 as P_i Q_i^T (n_i x r_i and n_{i+1} x r_i).
  std::vector<Split> p;
  std::vector<Split> q;
  std::vector<Index> rank;
  // With several cases, each row's solution with the cases side by side within each entry
  // (BackSubstituteCases), and C the same way.
  std::vector<Split> u_cases;
  Split c_cases;
  std::vector<double> scratch;  // SolveUnitUpperSplitCases' dot products
  Split s;  // [S; C^T], (r + cases) x r: S = V^T D V, C = V^T D W (a column per case)
  Split t;  // Q S, m x r
  Split y;  // a row's residual; a case's outputs in a group (`outputs` long)
  Split small;

  void Reserve(int nc_, int rows_, int cases_, std::size_t outputs) {
    if (BlockWorkspace::Reserve(nc_, rows_, cases_)) {
      const Index n = nc;
      const Index k = cases;
      p.assign(rows, Split{});
      q.assign(rows, Split{});
      u_cases.assign(rows, Split{});
      for (int i = 0; i < rows; ++i) {
        p[i].Resize(n * n);
        q[i].Resize(n * n);
        if (k > 1) u_cases[i].Resize(n * k);
      }
      c_cases.Resize(n * k);
      scratch.assign(static_cast<std::size_t>(2 * k), 0.0);
      rank.assign(rows, 0);
      s.Resize((n + k) * n);
      t.Resize(n * n);
      y.Resize(n);
      small.Resize(n);
    }
    if (y.re.size() < outputs) y.Resize(static_cast<Index>(outputs));
  }
};

namespace {

// Row i's pivot block factored, its Schur complement on row i + 1: F_{i+1} = A_{i+1} -
// Q_i S_i Q_i^T and the carried right-hand sides R_{i+1} - Q_i C_i (EliminateRows).
COMBABC_KERNEL void UpdateNextRow(SectionWorkspace& ws, int i, Index cases) {
  const Index nc = ws.nc;
  const Index n = ws.RowSize(i);
  const Index r = ws.rank[i];
  const Index ld = n + r + cases;
  const double* fr = ws.factor[i].re.data();
  const double* fi = ws.factor[i].im.data();
  // [S; C^T] = sum_j d_j [v_j; w_j] v_j^T, v_j^T and w_j^T the carried rows of column j; S is
  // symmetric: the lower triangle, then mirrored.
  double* sr = ws.s.re.data();
  double* si = ws.s.im.data();
  const Index ls = r + cases;
  std::fill(sr, sr + ls * r, 0.0);
  std::fill(si, si + ls * r, 0.0);
  for (Index j = 0; j < n; ++j) {
    const double* xr = fr + j * ld + n;
    const double* xi = fi + j * ld + n;
    const double dr = fr[j * ld + j];
    const double di = fi[j * ld + j];
    for (Index l = 0; l < r; ++l) {
      // -(d v_l): SubScaledSplit subtracts.
      SubScaledSplit(sr + l * ls + l,
                     si + l * ls + l,
                     xr + l,
                     xi + l,
                     -(dr * xr[l] - di * xi[l]),
                     -(dr * xi[l] + di * xr[l]),
                     ls - l);
    }
  }
  for (Index l = 0; l < r; ++l) {
    for (Index k = 0; k < l; ++k) {
      sr[l * ls + k] = sr[k * ls + l];
      si[l * ls + k] = si[k * ls + l];
    }
  }
  // T = Q S (m x r).
  const Index m = ws.RowSize(i + 1);
  const Index rn = ws.rank[i + 1];
  const Index ldn = m + rn + cases;
  const double* qr = ws.q[i].re.data();
  const double* qi = ws.q[i].im.data();
  double* tr = ws.t.re.data();
  double* ti = ws.t.im.data();
  std::fill(tr, tr + m * r, 0.0);
  std::fill(ti, ti + m * r, 0.0);
  for (Index l = 0; l < r; ++l) {
    Index k = 0;
    for (; k + 1 < r; k += 2) {
      SubScaled2Split(tr + l * m,
                      ti + l * m,
                      qr + k * m,
                      qi + k * m,
                      -sr[l * ls + k],
                      -si[l * ls + k],
                      qr + (k + 1) * m,
                      qi + (k + 1) * m,
                      -sr[l * ls + k + 1],
                      -si[l * ls + k + 1],
                      m);
    }
    if (k < r) {
      SubScaledSplit(
          tr + l * m, ti + l * m, qr + k * m, qi + k * m, -sr[l * ls + k], -si[l * ls + k], m);
    }
  }
  // F_{i+1} = A_{i+1} - T Q^T (lower triangle; FactorLdltSplit reads only that), and its
  // carried right-hand sides R_{i+1} - Q C.
  double* nr = ws.factor[i + 1].re.data();
  double* ni = ws.factor[i + 1].im.data();
  for (Index c = 0; c < m; ++c) {
    // Q(c, l) for this column, contiguous for SubScaledManySplit.
    double* qcr = ws.small.re.data();
    double* qci = ws.small.im.data();
    for (Index l = 0; l < r; ++l) {
      qcr[l] = qr[l * m + c];
      qci[l] = qi[l * m + c];
    }
    SubScaledManySplit(nr + c * ldn + c, ni + c * ldn + c, tr + c, ti + c, m, qcr, qci, r, m - c);
  }
  // Each case's R_{i+1} - Q C by columns of Q: an axpy per column, each entry taking the same
  // operations in the same order as a dot product over the columns would, without a latency
  // chain through them.
  for (Index j = 0; j < cases; ++j) {
    double* br = ws.small.re.data();
    double* bi = ws.small.im.data();
    std::copy_n(ws.rhs[i + 1].re.data() + j * nc, m, br);
    std::copy_n(ws.rhs[i + 1].im.data() + j * nc, m, bi);
    for (Index k = 0; k < r; ++k) {
      SubScaledSplit(br, bi, qr + k * m, qi + k * m, sr[k * ls + r + j], si[k * ls + r + j], m);
    }
    for (Index c = 0; c < m; ++c) {
      nr[c * ldn + m + rn + j] = br[c];
      ni[c * ldn + m + rn + j] = bi[c];
    }
  }
}

// Block LDL^T elimination of the assembled rows: F_0 = A_0; F_{i+1} = A_{i+1} - U_i^T F_i^{-1} U_i.
// With U_i = P_i Q_i^T, V_i = D_i^{-1} L_i^{-1} P_i (from the factorization's carried rows) and
// S_i = V_i^T D_i V_i: U_i^T F_i^{-1} U_i = Q_i S_i Q_i^T. The right-hand sides, one per load
// case, are eliminated alongside: row i's carried last rows become W_i = D_i^{-1} L_i^{-1} R'_i,
// and R'_{i+1} = R_{i+1} - Q_i C_i with C_i = V_i^T D_i W_i. Every case's column is carried
// through the same factorization: each costs its own rows of the updates, nothing more. False
// where a pivot breaks down.
COMBABC_KERNEL bool EliminateRows(SectionWorkspace& ws, Index cases, bool higham) {
  const Index nc = ws.nc;
  const int rows = ws.num_rows;
  bool ok = true;
  for (int i = 0; i < rows && ok; ++i) {
    const Index n = ws.RowSize(i);
    const Index r = ws.rank[i];
    const Index ld = n + r + cases;
    double* fr = ws.factor[i].re.data();
    double* fi = ws.factor[i].im.data();
    if (i == 0) {
      for (Index j = 0; j < cases; ++j) {
        for (Index c = 0; c < n; ++c) {
          fr[c * ld + n + r + j] = ws.rhs[0].re[j * nc + c];
          fi[c * ld + n + r + j] = ws.rhs[0].im[j * nc + c];
        }
      }
    }
    for (Index l = 0; l < r; ++l) {
      for (Index k = 0; k < n; ++k) {
        fr[k * ld + n + l] = ws.p[i].re[l * n + k];
        fi[k * ld + n + l] = ws.p[i].im[l * n + k];
      }
    }
    ok = FactorLdltSplit(fr, fi, ld, ld, n, higham);
    if (!ok || i + 1 == rows) break;
    UpdateNextRow(ws, i, cases);
  }
  return ok;
}

// Back substitution of one case: u_i = L_i^{-T} (w_i - V_i Q_i^T u_{i+1}).
COMBABC_KERNEL void BackSubstituteOne(SectionWorkspace& ws) {
  for (int i = ws.num_rows - 1; i >= 0; --i) {
    const Index n = ws.RowSize(i);
    const Index r = ws.rank[i];
    const Index ld = n + r + 1;
    const double* fr = ws.factor[i].re.data();
    const double* fi = ws.factor[i].im.data();
    double* yr = ws.u[i].re.data();
    double* yi = ws.u[i].im.data();
    double* cr = ws.small.re.data();
    double* ci = ws.small.im.data();
    if (r > 0) {
      const Index m = ws.RowSize(i + 1);
      for (Index l = 0; l < r; ++l) {
        DotSplit(ws.q[i].re.data() + l * m,
                 ws.q[i].im.data() + l * m,
                 ws.u[i + 1].re.data(),
                 ws.u[i + 1].im.data(),
                 m,
                 cr + l,
                 ci + l);
      }
    }
    for (Index j = 0; j < n; ++j) {
      // w_j - v_j^T c, both carried in column j below the pivot block.
      double vr = 0.0;
      double vi = 0.0;
      DotSplit(fr + j * ld + n, fi + j * ld + n, cr, ci, r, &vr, &vi);
      yr[j] = fr[j * ld + n + r] - vr;
      yi[j] = fi[j * ld + n + r] - vi;
    }
    SolveUnitUpperSplit(fr, fi, ld, n, yr, yi);
  }
}

// The same for several cases at once: the cases side by side within each entry (u_cases,
// c_cases), so that every dot product runs the cases as independent lanes (DotSplitCases). Each
// case gets BackSubstituteOne's bits; one case alone takes BackSubstituteOne, whose loops are not
// spread over lanes of one.
COMBABC_KERNEL void BackSubstituteCases(SectionWorkspace& ws, Index cases) {
  const Index nc = ws.nc;
  double* dots = ws.scratch.data();
  double* cr = ws.c_cases.re.data();
  double* ci = ws.c_cases.im.data();
  for (int i = ws.num_rows - 1; i >= 0; --i) {
    const Index n = ws.RowSize(i);
    const Index r = ws.rank[i];
    const Index ld = n + r + cases;
    const double* fr = ws.factor[i].re.data();
    const double* fi = ws.factor[i].im.data();
    double* yr = ws.u_cases[i].re.data();
    double* yi = ws.u_cases[i].im.data();
    if (r > 0) {
      const Index m = ws.RowSize(i + 1);
      for (Index l = 0; l < r; ++l) {
        DotSplitCases(ws.q[i].re.data() + l * m,
                      ws.q[i].im.data() + l * m,
                      ws.u_cases[i + 1].re.data(),
                      ws.u_cases[i + 1].im.data(),
                      m,
                      cases,
                      cr + l * cases,
                      ci + l * cases);
      }
    }
    for (Index j = 0; j < n; ++j) {
      // w_j - v_j^T c, both carried in column j below the pivot block (w_j of every case
      // side by side).
      double* vr = yr + j * cases;
      double* vi = yi + j * cases;
      DotSplitCases(fr + j * ld + n, fi + j * ld + n, cr, ci, r, cases, vr, vi);
      for (Index c = 0; c < cases; ++c) {
        vr[c] = fr[j * ld + n + r + c] - vr[c];
        vi[c] = fi[j * ld + n + r + c] - vi[c];
      }
    }
    SolveUnitUpperSplitCases(fr, fi, ld, n, yr, yi, cases, dots);
    for (Index c = 0; c < cases; ++c) {
      for (Index j = 0; j < n; ++j) {
        ws.u[i].re[c * nc + j] = yr[j * cases + c];
        ws.u[i].im[c * nc + j] = yi[j * cases + c];
      }
    }
  }
}

// Back substitution of every case: one alone by BackSubstituteOne, several side by side.
COMBABC_KERNEL void BackSubstitute(SectionWorkspace& ws, Index cases) {
  if (cases == 1) BackSubstituteOne(ws);
  if (cases > 1) BackSubstituteCases(ws, cases);
}

// The residual check of every case (FlagLargeResiduals), with the couplings in factored form:
// row i's residual takes P_i Q_i^T u_{i+1} + Q_{i-1} P_{i-1}^T u_{i-1}.
COMBABC_KERNEL void FlagLargeRowResiduals(SectionWorkspace& ws, Index cases) {
  double* cr = ws.small.re.data();
  double* ci = ws.small.im.data();
  const auto add_couplings = [&](int i, Index at, double* zr, double* zi) COMBABC_KERNEL_LAMBDA {
    const Index n = ws.RowSize(i);
    const auto couple =
        [&](const Split& a, const Split& b, Index k, Index nb, int j) COMBABC_KERNEL_LAMBDA {
          for (Index l = 0; l < k; ++l) {
            DotSplit(b.re.data() + l * nb,
                     b.im.data() + l * nb,
                     ws.u[j].re.data() + at,
                     ws.u[j].im.data() + at,
                     nb,
                     cr + l,
                     ci + l);
            SubScaledSplit(zr, zi, a.re.data() + l * n, a.im.data() + l * n, -cr[l], -ci[l], n);
          }
        };
    if (i + 1 < ws.num_rows) couple(ws.p[i], ws.q[i], ws.rank[i], ws.RowSize(i + 1), i + 1);
    if (i > 0) couple(ws.q[i - 1], ws.p[i - 1], ws.rank[i - 1], ws.RowSize(i - 1), i - 1);
  };
  FlagLargeResiduals(ws, cases, ws.y.re.data(), ws.y.im.data(), add_couplings);
}

// A certified (Higham) system: the elimination is backward stable; only a non-finite result
// (non-finite input) sends a case to the fallback.
COMBABC_KERNEL void FlagNonFiniteResults(SectionWorkspace& ws, Index cases) {
  const Index nc = ws.nc;
  for (Index j = 0; j < cases; ++j) {
    double sum = 0.0;
    for (int i = 0; i < ws.num_rows; ++i) {
      for (Index k = 0; k < ws.RowSize(i); ++k) {
        sum += ws.u[i].re[j * nc + k] + ws.u[i].im[j * nc + k];
      }
    }
    ws.fallback[j] = std::isfinite(sum) ? 0 : 1;
  }
}

// Fallback: one dense partial-pivoting LU of the whole condensed system (ws.diagonal holds the
// assembled diagonal blocks), solved for each case flagged in ws.fallback.
inline void SolvePivoting(SectionWorkspace& ws, Index cases) {
  const int rows = ws.num_rows;
  const auto complex_matrix = [](const Split& a, Index rows_a, Index cols_a, Index ld) {
    Eigen::MatrixXcd out(rows_a, cols_a);
    for (Index c = 0; c < cols_a; ++c) {
      for (Index k = 0; k < rows_a; ++k) out(k, c) = {a.re[c * ld + k], a.im[c * ld + k]};
    }
    return out;
  };
  const std::vector<Index> offset = RowOffsets(ws);
  Eigen::MatrixXcd big = Eigen::MatrixXcd::Zero(offset[rows], offset[rows]);
  for (int i = 0; i < rows; ++i) {
    const Index n = ws.RowSize(i);
    const Eigen::MatrixXcd a = complex_matrix(ws.diagonal[i], n, n, n);
    auto block = big.block(offset[i], offset[i], n, n);
    block.triangularView<Eigen::Lower>() = a;
    block.triangularView<Eigen::StrictlyUpper>() = a.transpose();
    if (i + 1 < rows) {
      const Index m = ws.RowSize(i + 1);
      const Index r = ws.rank[i];
      const Eigen::MatrixXcd coupling =
          complex_matrix(ws.p[i], n, r, n) * complex_matrix(ws.q[i], m, r, m).transpose();
      big.block(offset[i], offset[i + 1], n, m) = coupling;
      big.block(offset[i + 1], offset[i], m, n) = coupling.transpose();
    }
  }
  SolveFlaggedCases(ws, cases, offset, Eigen::PartialPivLU<Eigen::MatrixXcd>(big));
}

}  // namespace

void SectionCondensation::Solve(std::span<const std::uint8_t> clamps,
                                std::span<std::complex<double>> w) const {
  switch (kernels_) {
    case VectorKernels::kAvx512:
      SolveAvx512(clamps, w);
      return;
    case VectorKernels::kAvx2:
      SolveAvx2(clamps, w);
      return;
    case VectorKernels::kAuto:
    case VectorKernels::kPortable:
      SolvePortable(clamps, w);
      return;
  }
}

void SectionCondensation::SolvePortable(std::span<const std::uint8_t> clamps,
                                        std::span<std::complex<double>> w) const {
  SolveBody(clamps, w);
}

COMBABC_TARGET_AVX2 void SectionCondensation::SolveAvx2(std::span<const std::uint8_t> clamps,
                                                        std::span<std::complex<double>> w) const {
  SolveBody(clamps, w);
}

COMBABC_TARGET_AVX512 void SectionCondensation::SolveAvx512(
    std::span<const std::uint8_t> clamps, std::span<std::complex<double>> w) const {
  SolveBody(clamps, w);
}

COMBABC_KERNEL void SectionCondensation::SolveBody(std::span<const std::uint8_t> clamps,
                                                   std::span<std::complex<double>> w) const {
  const int ng = layout_->num_sections() / group_size_;
  const Index cases = layout_->num_cases();
  // The whole plate in one group was solved in the precompute; singular there is singular here.
  for (int g = 0; g < ng; ++g) {
    const double singular = GroupPieceOf(g, clamps).singular;
    if (singular > 0.0) throw SingularSystem(singular);
  }
  thread_local SectionWorkspace ws;
  ws.Reserve(layout_->nc(), std::max(ng - 1, 1), layout_->num_cases(), w.size());
  ws.num_rows = ng - 1;  // inner group boundaries c = 1..ng-1 are rows c - 1
  // Each A_i goes into the lower triangle of its factorization's storage: straight there for a
  // certified system; otherwise first into storage of its own, which the residual check reads.
  const bool in_place = higham_ && !always_pivot_;
  Assemble(clamps, in_place, ws);
  // One factorization for every load case (EliminateRows), then each case's back substitution.
  // A pivot that breaks down sends every case to the fallback; a case whose own result fails
  // goes there alone, so that each case is solved as a model of it alone would solve it.
  ws.fallback.assign(static_cast<std::size_t>(cases), 1);
  if (!always_pivot_ && EliminateRows(ws, cases, higham_)) {
    BackSubstitute(ws, cases);
    if (higham_) {
      FlagNonFiniteResults(ws, cases);
    } else {
      FlagLargeRowResiduals(ws, cases);
    }
  }
  if (ws.AnyFallback()) FallBack(clamps, in_place, ws);
  ThrowIfSingular(ws, cases);
  for (int g = 0; g < ng; ++g) RecoverGroupOutputs(clamps, g, ws, w);
}

// The free dofs of each row (SectionLayout::FreeDofs: a node on edge A (B) is fixed when either
// adjoining section fixes it). Row i gets the right block of group i and the left block of group
// i + 1 (lower triangles only: the blocks are symmetric) and the loads of both and of its own
// cross-section; the coupling of rows i and i + 1 is group i + 1's, in its factored form.
// `in_place`: each A_i straight into its factorization's storage, else into ws.diagonal first.
COMBABC_KERNEL void SectionCondensation::Assemble(std::span<const std::uint8_t> clamps,
                                                  bool in_place,
                                                  SectionWorkspace& ws) const {
  const int nc = layout_->nc();
  const Index cases = layout_->num_cases();
  const int rows = ws.num_rows;
  const ClampPattern pattern(clamps, layout_->num_sections());
  for (int i = 0; i < rows; ++i) ws.free[i] = &layout_->FreeDofs((i + 1) * group_size_, pattern);
  for (int i = 0; i < rows; ++i) {
    const SolvePiece& left = GroupPieceOf(i, clamps);
    const SolvePiece& right = GroupPieceOf(i + 1, clamps);
    const std::vector<int>& f = *ws.free[i];
    const Index n = ws.RowSize(i);
    ws.rank[i] = i + 1 < rows ? right.coupling_left.re.cols() : 0;
    const Index ld = n + ws.rank[i] + cases;
    double* fr = ws.factor[i].re.data();
    double* fi = ws.factor[i].im.data();
    if (in_place) {
      AssembleDiagonal(clamps, i, ws, fr, fi, ld);
    } else {
      double* ar = ws.diagonal[i].re.data();
      double* ai = ws.diagonal[i].im.data();
      AssembleDiagonal(clamps, i, ws, ar, ai, n);
      ws.diagonal_max2[i] = LowerMaxNorm2Split(ar, ai, n, n);  // residual scale
      for (Index c = 0; c < n; ++c) {
        std::copy(ar + c * n + c, ar + (c + 1) * n, fr + c * ld + c);
        std::copy(ai + c * n + c, ai + (c + 1) * n, fi + c * ld + c);
      }
    }
    const auto boundary = static_cast<std::size_t>(i + 1) * static_cast<std::size_t>(group_size_);
    for (Index j = 0; j < cases; ++j) {
      for (Index k = 0; k < n; ++k) {
        const std::complex<double> v = left.load(left.left_size + f[k], j) + right.load(f[k], j) +
                                       boundary_load_[boundary](f[k], j);
        ws.rhs[i].re[j * nc + k] = v.real();
        ws.rhs[i].im[j * nc + k] = v.imag();
      }
    }
    if (i + 1 < rows) {
      const std::vector<int>& g = *ws.free[i + 1];
      const Index m = ws.RowSize(i + 1);
      const Index r = ws.rank[i];
      for (Index l = 0; l < r; ++l) {
        const double* pr = right.coupling_left.re.data() + l * nc;
        const double* pi = right.coupling_left.im.data() + l * nc;
        const double* qr = right.coupling_right.re.data() + l * nc;
        const double* qi = right.coupling_right.im.data() + l * nc;
        for (Index k = 0; k < n; ++k) {
          ws.p[i].re[l * n + k] = pr[f[k]];
          ws.p[i].im[l * n + k] = pi[f[k]];
        }
        for (Index k = 0; k < m; ++k) {
          ws.q[i].re[l * m + k] = qr[g[k]];
          ws.q[i].im[l * m + k] = qi[g[k]];
        }
      }
    }
  }
}

// The lower triangle of row i's diagonal block, A = right block of the group on its left + left
// block of the group on its right, at the row's free dofs f, into (ar, ai) with leading dimension
// ld. The free dofs are a contiguous run (a clamp fixes whole edge nodes, the first or last of a
// cross-section) unless a mask fixes only some of a node's dofs.
COMBABC_KERNEL void SectionCondensation::AssembleDiagonal(std::span<const std::uint8_t> clamps,
                                                          int i,
                                                          const SectionWorkspace& ws,
                                                          double* ar,
                                                          double* ai,
                                                          std::ptrdiff_t ld) const {
  const SolvePiece& left = GroupPieceOf(i, clamps);
  const SolvePiece& right = GroupPieceOf(i + 1, clamps);
  const std::vector<int>& f = *ws.free[i];
  const Index nc = layout_->nc();
  const auto n = static_cast<Index>(f.size());
  const bool run = n > 0 && f[n - 1] - f[0] + 1 == n;
  for (Index c = 0; c < n; ++c) {
    const Index column = Index{f[c]} * nc;
    const double* lr = left.right_block.re.data() + column;
    const double* li = left.right_block.im.data() + column;
    const double* rr = right.left_block.re.data() + column;
    const double* ri = right.left_block.im.data() + column;
    if (run) {
      const Index first = f[c];
      for (Index r = c; r < n; ++r) {
        ar[c * ld + r] = lr[first + r - c] + rr[first + r - c];
        ai[c * ld + r] = li[first + r - c] + ri[first + r - c];
      }
    } else {
      for (Index r = c; r < n; ++r) {
        ar[c * ld + r] = lr[f[r]] + rr[f[r]];
        ai[c * ld + r] = li[f[r]] + ri[f[r]];
      }
    }
  }
}

// The cases flagged in ws.fallback by the pivoting LU. Assembled in place, the diagonal blocks
// went into the factorization, which overwrote them: assembled again first.
COMBABC_KERNEL void SectionCondensation::FallBack(std::span<const std::uint8_t> clamps,
                                                  bool in_place,
                                                  SectionWorkspace& ws) const {
  if (in_place) {
    for (int i = 0; i < ws.num_rows; ++i) {
      AssembleDiagonal(
          clamps, i, ws, ws.diagonal[i].re.data(), ws.diagonal[i].im.data(), ws.RowSize(i));
    }
  }
  SolvePivoting(ws, layout_->num_cases());
}

// Every case's outputs in group g from its kept end cross-sections (rows g - 1 and g): the
// case's offsets plus the output map's rows of its set, at the columns of the free end dofs
// (fixed ones are zero), times that case's values there.
COMBABC_KERNEL void SectionCondensation::RecoverGroupOutputs(
    std::span<const std::uint8_t> clamps,
    int g,
    SectionWorkspace& ws,
    std::span<std::complex<double>> w) const {
  const SolvePiece& piece = GroupPieceOf(g, clamps);
  const OutputLayout& layout = group_layout_[g];
  const OutputSets& sets = layout_->sets();
  const Index nc = ws.nc;
  const Index map_rows = piece.output_map.re.rows();
  double* vr = ws.y.re.data();
  double* vi = ws.y.im.data();
  for (int c = 0; c < sets.num_cases(); ++c) {
    const std::vector<int>& positions = layout.positions[sets.set_of_case[c]];
    const auto n_out = static_cast<Index>(positions.size());
    if (n_out == 0) continue;
    const Index first_row = layout.map_begin[sets.set_of_case[c]];
    const Index first_offset = layout.offset_begin[c];
    for (Index k = 0; k < n_out; ++k) {
      vr[k] = piece.output_offset(first_offset + k).real();
      vi[k] = piece.output_offset(first_offset + k).imag();
    }
    // v += (the output map's columns of end cross-section i's free dofs) u_i. SubScaled*Split
    // subtracts, so the multipliers are -u.
    const auto add_end = [&](int i, Index offset) COMBABC_KERNEL_LAMBDA {
      const std::vector<int>& f = *ws.free[i];
      const Index n = ws.RowSize(i);
      const double* mr = piece.output_map.re.data() + first_row;
      const double* mi = piece.output_map.im.data() + first_row;
      double* sr = ws.small.re.data();
      double* si = ws.small.im.data();
      for (Index k = 0; k < n; ++k) {
        sr[k] = -ws.u[i].re[c * nc + k];
        si[k] = -ws.u[i].im[c * nc + k];
      }
      if (n > 0 && f[n - 1] - f[0] + 1 == n) {
        // A contiguous run of free dofs is a run of adjacent columns: several per pass over v.
        const Index column = (offset + f[0]) * map_rows;
        SubScaledManySplit(vr, vi, mr + column, mi + column, map_rows, sr, si, n, n_out);
      } else {
        for (Index k = 0; k < n; ++k) {
          const Index column = (offset + f[k]) * map_rows;
          SubScaledSplit(vr, vi, mr + column, mi + column, sr[k], si[k], n_out);
        }
      }
    };
    if (piece.left_size > 0) add_end(g - 1, 0);
    if (piece.right_size > 0) add_end(g, piece.left_size);
    std::complex<double>* out = w.data() + sets.first_output[c];
    for (Index k = 0; k < n_out; ++k) out[positions[k]] = {vr[k], vi[k]};
  }
}

}  // namespace combabc::plate
