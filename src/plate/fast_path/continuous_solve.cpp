// The per-call solve with continuous unknowns (docs/model.md, "Continuous unknowns"): evaluate the
// section pieces of the clamp states this configuration uses at its mu (series or direct, see
// continuous_condensation.hpp), then solve the block-tridiagonal system on the num_sections + 1
// cross-sections. Unlike the clamp-only fast path there are no group pieces (64 states per group
// at every mu would cost more than the chain they save) and the couplings are full blocks (a
// section's end-to-end coupling has full numerical rank: 5 cm of strip damp its cross-section
// shapes only to 1e-16). The block elimination is the same unpivoted complex-symmetric LDL^T with
// a residual check (block_ldlt.hpp); the fallback is a sparse LU of the assembled system. Every
// load case's right-hand side rides through the one factorization (a column each). As in
// section_solve.cpp, all the per-call algebra of the elimination runs on split real/imaginary
// arrays in plain loops (the Schur update V^T D V four pivots per pass); the workspace is per
// thread and reused.
//
// SolveBody runs the phases in order: evaluate the pieces the configuration uses (EvaluatePieces),
// assemble the chain (Assemble), eliminate (EliminateChain), back-substitute
// (BackSubstituteChain), check the results (FlagLargeChainResiduals), fall back for the cases that
// need it (SolveChainPivoting), refuse a singular system (ThrowIfSingular) and recover the outputs
// (RecoverOutputs).
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <vector>

#include <Eigen/SparseLU>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "plate/fast_path/block_ldlt.hpp"
#include "plate/fast_path/continuous_condensation.hpp"

namespace combabc::plate {

// One call's section pieces: per (mesh, state) the packed piece (PackPiece); per (distinct
// section, state) its table's rows (SectionData): the output map (n_out x 2 nc by columns), then
// for each case with an interior load there, its load (2 nc) and its output offsets.
struct ContinuousCondensation::Evaluated {
  std::vector<char> state_needed;
  std::vector<char> kind_needed;
  std::vector<Eigen::VectorXcd> piece;
  std::vector<Eigen::VectorXcd> section;
  Eigen::MatrixXd acc;  // real and imaginary parts of a table's sum
};

// Solve's per-thread workspace: the block rows (BlockWorkspace) and the couplings between them.
struct ContinuousWorkspace : BlockWorkspace {
  std::vector<Split> coupling;  // U_c between rows c and c + 1 (n_c x n_{c+1})
  std::vector<int> state;       // each section's clamp state
  Split dv;  // D_c V_c (n x m, leading dimension n): column l holds d_j v_jl over the pivots j
  Split w;   // W_c gathered from the factor's carried last rows (n x cases)
  Split z;   // one row's residual
  Eigen::VectorXcd ends;
  Eigen::VectorXcd values;

  void Reserve(int nc_, int rows_, int cases_) {
    if (!BlockWorkspace::Reserve(nc_, rows_, cases_)) return;
    const Index n = nc;
    const Index k = cases;
    coupling.assign(rows, Split{});
    for (int c = 0; c < rows; ++c) coupling[c].Resize(n * n);
    dv.Resize(n * n);
    w.Resize(n * k);
    z.Resize(n);
    ends.resize(2 * n);
  }
};

namespace {

using Complex = std::complex<double>;

// out = sum_{j < columns} (-mu)^j V_j for the table V = re + i im (im empty when K_base is real):
// one pass over the table's columns (the memory traffic bounds this step), accumulating the real
// and imaginary parts, which stay in cache. (A matrix product against the powers would first copy
// the table into Eigen's packed layout.)
void EvaluateTable(const Eigen::MatrixXd& re,
                   const Eigen::MatrixXd& im,
                   Eigen::Index columns,
                   Complex mu,
                   Eigen::MatrixXd* acc,
                   Eigen::VectorXcd* out) {
  columns = std::min(columns, re.cols());
  const Eigen::Index rows = re.rows();
  acc->resize(rows, 2);
  acc->setZero();
  Complex p = 1.0;
  for (Eigen::Index j = 0; j < columns; ++j, p *= -mu) {
    acc->col(0) += p.real() * re.col(j);
    acc->col(1) += p.imag() * re.col(j);
    if (im.size() > 0) {  // (a + i b) (x + i y) = a x - b y + i (a y + b x)
      acc->col(0) -= p.imag() * im.col(j);
      acc->col(1) += p.real() * im.col(j);
    }
  }
  out->resize(rows);
  out->real() = acc->col(0);
  out->imag() = acc->col(1);
}

// Block LDL^T elimination of the chain: F_0 = A_0, F_{c+1} = A_{c+1} - U_c^T F_c^{-1} U_c.
// FactorLdltSplit turns the carried rows U_c^T and R'_c^T into V_c^T = (D^{-1} L^{-1} U_c)^T
// and W_c^T (a column per load case), so that U_c^T F_c^{-1} U_c = V_c^T D V_c and
// R'_{c+1} = R_{c+1} - V_c^T D W_c. False where a pivot breaks down.
COMBABC_KERNEL bool EliminateChain(ContinuousWorkspace& ws, Index cases) {
  const Index nc = ws.nc;
  const int rows = ws.num_rows;
  bool ok = true;
  for (int c = 0; c < rows && ok; ++c) {
    const Index n = ws.RowSize(c);
    const Index m = ws.RowSize(c + 1);
    const Index ld = n + m + cases;
    double* fr = ws.factor[c].re.data();
    double* fi = ws.factor[c].im.data();
    if (c == 0) {
      const double* ar = ws.diagonal[0].re.data();
      const double* ai = ws.diagonal[0].im.data();
      for (Index j = 0; j < n; ++j) {
        std::copy(ar + j * n + j, ar + (j + 1) * n, fr + j * ld + j);
        std::copy(ai + j * n + j, ai + (j + 1) * n, fi + j * ld + j);
        for (Index k = 0; k < cases; ++k) {
          fr[j * ld + n + m + k] = ws.rhs[0].re[k * nc + j];
          fi[j * ld + n + m + k] = ws.rhs[0].im[k * nc + j];
        }
      }
    }
    for (Index l = 0; l < m; ++l) {
      for (Index k = 0; k < n; ++k) {
        fr[k * ld + n + l] = ws.coupling[c].re[l * n + k];
        fi[k * ld + n + l] = ws.coupling[c].im[l * n + k];
      }
    }
    ok = FactorLdltSplit(fr, fi, ld, ld, n);
    if (!ok || m == 0) break;
    // D V (by columns of V, so that each Schur column's scalars are contiguous) and W.
    double* dvr = ws.dv.re.data();
    double* dvi = ws.dv.im.data();
    double* wr = ws.w.re.data();
    double* wi = ws.w.im.data();
    for (Index j = 0; j < n; ++j) {
      const double dr = fr[j * ld + j];
      const double di = fi[j * ld + j];
      const double* xr = fr + j * ld + n;
      const double* xi = fi + j * ld + n;
      for (Index l = 0; l < m; ++l) {
        dvr[l * n + j] = dr * xr[l] - di * xi[l];
        dvi[l * n + j] = dr * xi[l] + di * xr[l];
      }
      for (Index k = 0; k < cases; ++k) {
        wr[k * n + j] = xr[m + k];
        wi[k * n + j] = xi[m + k];
      }
    }
    // F_{c+1} = A_{c+1} - V^T D V, column l of its lower triangle at a time (FactorLdltSplit
    // reads only that): v_j (rows l..m-1) times d_j v_jl, four pivots per pass; and its carried
    // right-hand sides R_{c+1} - V^T D W.
    const Index m2 = ws.RowSize(c + 2);
    const Index ldn = m + m2 + cases;
    double* nr = ws.factor[c + 1].re.data();
    double* ni = ws.factor[c + 1].im.data();
    const double* ar = ws.diagonal[c + 1].re.data();
    const double* ai = ws.diagonal[c + 1].im.data();
    for (Index l = 0; l < m; ++l) {
      double* cr = nr + l * ldn + l;
      double* ci = ni + l * ldn + l;
      std::copy(ar + l * m + l, ar + (l + 1) * m, cr);
      std::copy(ai + l * m + l, ai + (l + 1) * m, ci);
      SubScaledManySplit(cr, ci, fr + n + l, fi + n + l, ld, dvr + l * n, dvi + l * n, n, m - l);
      for (Index k = 0; k < cases; ++k) {
        double br = 0.0;
        double bi = 0.0;
        DotSplit(dvr + l * n, dvi + l * n, wr + k * n, wi + k * n, n, &br, &bi);
        nr[l * ldn + m + m2 + k] = ws.rhs[c + 1].re[k * nc + l] - br;
        ni[l * ldn + m + m2 + k] = ws.rhs[c + 1].im[k * nc + l] - bi;
      }
    }
  }
  return ok;
}

// Back substitution of every case: u_c = L_c^{-T} (w_c - V_c u_{c+1}).
COMBABC_KERNEL void BackSubstituteChain(ContinuousWorkspace& ws, Index cases) {
  const Index nc = ws.nc;
  for (int c = ws.num_rows - 1; c >= 0; --c) {
    const Index n = ws.RowSize(c);
    const Index m = ws.RowSize(c + 1);
    const Index ld = n + m + cases;
    const double* fr = ws.factor[c].re.data();
    const double* fi = ws.factor[c].im.data();
    for (Index k = 0; k < cases; ++k) {
      double* yr = ws.u[c].re.data() + k * nc;
      double* yi = ws.u[c].im.data() + k * nc;
      for (Index j = 0; j < n; ++j) {
        // w_j - v_j^T u_{c+1}, both carried in column j below the pivot block.
        double vr = 0.0;
        double vi = 0.0;
        if (m > 0) {
          DotSplit(fr + j * ld + n,
                   fi + j * ld + n,
                   ws.u[c + 1].re.data() + k * nc,
                   ws.u[c + 1].im.data() + k * nc,
                   m,
                   &vr,
                   &vi);
        }
        yr[j] = fr[j * ld + n + m + k] - vr;
        yi[j] = fi[j * ld + n + m + k] - vi;
      }
      SolveUnitUpperSplit(fr, fi, ld, n, yr, yi);
    }
  }
}

// The residual check of every case (FlagLargeResiduals), with full couplings: row c's residual
// takes U_c u_{c+1} + U_{c-1}^T u_{c-1}.
COMBABC_KERNEL void FlagLargeChainResiduals(ContinuousWorkspace& ws, Index cases) {
  const auto add_couplings = [&](int c, Index at, double* zr, double* zi) COMBABC_KERNEL_LAMBDA {
    const Index n = ws.RowSize(c);
    if (c + 1 < ws.num_rows) {
      const Split& a = ws.coupling[c];
      for (Index l = 0; l < ws.RowSize(c + 1); ++l) {
        SubScaledSplit(zr,
                       zi,
                       a.re.data() + l * n,
                       a.im.data() + l * n,
                       -ws.u[c + 1].re[at + l],
                       -ws.u[c + 1].im[at + l],
                       n);
      }
    }
    if (c > 0) {
      const Split& a = ws.coupling[c - 1];
      const Index p = ws.RowSize(c - 1);
      for (Index j = 0; j < n; ++j) {
        double vr = 0.0;
        double vi = 0.0;
        DotSplit(a.re.data() + j * p,
                 a.im.data() + j * p,
                 ws.u[c - 1].re.data() + at,
                 ws.u[c - 1].im.data() + at,
                 p,
                 &vr,
                 &vi);
        zr[j] += vr;
        zi[j] += vi;
      }
    }
  };
  FlagLargeResiduals(ws, cases, ws.z.re.data(), ws.z.im.data(), add_couplings);
}

// Fallback: one sparse partial-pivoting LU of the assembled block-tridiagonal system, solved for
// each case flagged in ws.fallback.
inline void SolveChainPivoting(ContinuousWorkspace& ws, Index cases) {
  const int rows = ws.num_rows;
  const std::vector<Index> offset = RowOffsets(ws);
  std::vector<Eigen::Triplet<Complex>> triplets;
  for (int c = 0; c < rows; ++c) {
    const Index n = ws.RowSize(c);
    const Split& a = ws.diagonal[c];
    for (Index j = 0; j < n; ++j) {
      for (Index i = j; i < n; ++i) {
        const Complex v(a.re[j * n + i], a.im[j * n + i]);
        triplets.emplace_back(offset[c] + i, offset[c] + j, v);
        if (i != j) triplets.emplace_back(offset[c] + j, offset[c] + i, v);
      }
    }
    if (c + 1 < rows) {
      const Split& u = ws.coupling[c];
      const Index m = ws.RowSize(c + 1);
      for (Index j = 0; j < m; ++j) {
        for (Index i = 0; i < n; ++i) {
          const Complex v(u.re[j * n + i], u.im[j * n + i]);
          triplets.emplace_back(offset[c] + i, offset[c + 1] + j, v);
          triplets.emplace_back(offset[c + 1] + j, offset[c] + i, v);
        }
      }
    }
  }
  Eigen::SparseMatrix<Complex> big(offset[rows], offset[rows]);
  big.setFromTriplets(triplets.begin(), triplets.end());
  big.makeCompressed();
  Eigen::SparseLU<Eigen::SparseMatrix<Complex>, Eigen::COLAMDOrdering<int>> lu;
  lu.compute(big);
  if (lu.info() != Eigen::Success) {
    throw Error(ErrorKind::kSoftware, "continuous condensation: singular condensed system");
  }
  SolveFlaggedCases(ws, cases, offset, lu);
}

}  // namespace

void ContinuousCondensation::EvaluateSeries(
    int mesh_kind, int state, int terms, Complex mu, Evaluated* e) const {
  const std::size_t index = static_cast<std::size_t>(mesh_kind) * 4 + state;
  const StateData& sd = states_[index];
  EvaluateTable(sd.table_re, sd.table_im, terms + 2, mu, &e->acc, &e->piece[index]);
  for (std::size_t kind = 0; kind < kind_section_.size(); ++kind) {
    const std::size_t k = kind * 4 + state;
    if (!e->kind_needed[k] || mesh_kind_[kind_section_[kind]] != mesh_kind) continue;
    const SectionData& sec = sections_[k];
    EvaluateTable(sec.table_re, sec.table_im, terms + 1, mu, &e->acc, &e->section[k]);
  }
}

void ContinuousCondensation::EvaluateDirect(int mesh_kind,
                                            int state,
                                            Complex mu,
                                            Evaluated* e) const {
  const int nc = layout_->nc();
  const std::size_t index = static_cast<std::size_t>(mesh_kind) * 4 + state;
  const StateData& sd = states_[index];
  const Eigen::MatrixXcd s_bb = sd.k_bb + mu * sd.m_bb;
  const Eigen::MatrixXcd s_ib = sd.k_ib + mu * sd.m_ib;
  e->piece[index].resize(PackedSize());
  if (s_ib.rows() == 0) {  // no interior
    PackPiece(s_bb, e->piece[index].data());
  }
  // S = K + mu M on the interior, Jacobi-scaled sparse LU; the boundary blocks are already in the
  // scaled cross-section dofs.
  Eigen::SparseMatrix<Complex> s_ii = sd.k_ii + mu * sd.m_ii;
  const Eigen::VectorXd scale = s_ii.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  s_ii = scale.asDiagonal() * s_ii * scale.asDiagonal();
  s_ii.makeCompressed();
  Eigen::SparseLU<Eigen::SparseMatrix<Complex>, Eigen::COLAMDOrdering<int>> lu;
  if (s_ib.rows() > 0) {
    lu.compute(s_ii);
    if (lu.info() != Eigen::Success) {
      throw Error(ErrorKind::kSoftware, "continuous condensation: singular interior matrix");
    }
  }
  const auto solve = [&](const auto& b) -> Eigen::MatrixXcd {
    return scale.asDiagonal() * lu.solve((scale.asDiagonal() * b).eval());
  };
  // Only the interior dofs next to the ends couple to them (sd.coupled), and the outputs read only
  // the dofs of their elements (sec.read): the products below skip the zero rows and columns.
  const std::vector<int>& coupled = sd.coupled;
  Eigen::MatrixXcd x = Eigen::MatrixXcd::Zero(s_ib.rows(), s_ib.cols());  // S_II^{-1} S_IB
  if (s_ib.rows() > 0) {
    x = solve(s_ib);
    PackPiece(s_bb - s_ib(coupled, Eigen::all).transpose() * x(coupled, Eigen::all),
              e->piece[index].data());
  }
  for (std::size_t kind = 0; kind < kind_section_.size(); ++kind) {
    const std::size_t k = kind * 4 + state;
    if (!e->kind_needed[k] || mesh_kind_[kind_section_[kind]] != mesh_kind) continue;
    const SectionData& sec = sections_[k];
    const OutputLayout& layout = layout_->SectionOutputs(kind_section_[kind]);
    Eigen::VectorXcd& out = e->section[k];
    out.resize(sec.table_re.rows());
    // The output maps set by set, each by a product of the shape a model of that set alone would
    // use (a product's blocking, hence its rounding, depends on its shape).
    for (int set = 0; set < layout_->sets().num_sets(); ++set) {
      const int first = layout.map_begin[set];
      const int rows = layout.map_begin[set + 1] - first;
      if (rows == 0) continue;
      Eigen::Map<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> map(out.data() + first,
                                                                rows,
                                                                2 * static_cast<Eigen::Index>(nc),
                                                                Eigen::OuterStride<>(sec.map_rows));
      map = sec.r_b.middleRows(first, rows) -
            sec.r_i(Eigen::seqN(first, rows), sec.read[set]) * x(sec.read[set], Eigen::all);
    }
    for (std::size_t l = 0; l < sec.loaded_cases.size(); ++l) {
      const Eigen::VectorXcd f = sec.f_i.col(static_cast<Eigen::Index>(l));
      const Eigen::VectorXcd y = solve(f);
      const int set = layout_->sets().set_of_case[sec.loaded_cases[l]];
      const int first = layout.map_begin[set];
      const int rows = layout.map_begin[set + 1] - first;
      out.segment(sec.loaded_start[l], 2 * nc) =
          -s_ib(coupled, Eigen::all).transpose() * y(coupled);
      out.segment(sec.loaded_start[l] + 2 * static_cast<Eigen::Index>(nc), rows) =
          sec.r_i(Eigen::seqN(first, rows), sec.read[set]) * y(sec.read[set]);
    }
  }
}

void ContinuousCondensation::Solve(std::span<const std::uint8_t> clamps,
                                   Complex mu,
                                   std::span<std::complex<double>> w) const {
  switch (kernels_) {
    case VectorKernels::kAvx512:
      SolveAvx512(clamps, mu, w);
      return;
    case VectorKernels::kAvx2:
      SolveAvx2(clamps, mu, w);
      return;
    case VectorKernels::kAuto:
    case VectorKernels::kPortable:
      SolvePortable(clamps, mu, w);
      return;
  }
}

void ContinuousCondensation::SolvePortable(std::span<const std::uint8_t> clamps,
                                           Complex mu,
                                           std::span<std::complex<double>> w) const {
  SolveBody(clamps, mu, w);
}

COMBABC_TARGET_AVX2 void ContinuousCondensation::SolveAvx2(
    std::span<const std::uint8_t> clamps, Complex mu, std::span<std::complex<double>> w) const {
  SolveBody(clamps, mu, w);
}

COMBABC_TARGET_AVX512 void ContinuousCondensation::SolveAvx512(
    std::span<const std::uint8_t> clamps, Complex mu, std::span<std::complex<double>> w) const {
  SolveBody(clamps, mu, w);
}

COMBABC_KERNEL void ContinuousCondensation::SolveBody(std::span<const std::uint8_t> clamps,
                                                      Complex mu,
                                                      std::span<std::complex<double>> w) const {
  const int ns = layout_->num_sections();
  const Index cases = layout_->num_cases();
  thread_local ContinuousWorkspace ws;
  thread_local Evaluated e;
  ws.Reserve(layout_->nc(), ns + 1, layout_->num_cases());
  ws.num_rows = ns + 1;  // every cross-section c = 0..ns is a row
  EvaluatePieces(clamps, mu, ws, e);
  Assemble(clamps, e, ws);
  // One factorization for every load case, each case's back substitution, and a residual check
  // of each. A pivot that breaks down sends every case to the sparse LU; a case whose residual
  // fails goes there alone, so that each case is solved as a model of it alone would solve it.
  ws.fallback.assign(static_cast<std::size_t>(cases), 1);
  if (!always_pivot_ && EliminateChain(ws, cases)) {
    BackSubstituteChain(ws, cases);
    FlagLargeChainResiduals(ws, cases);
  }
  if (ws.AnyFallback()) SolveChainPivoting(ws, cases);
  ThrowIfSingular(ws, cases);
  RecoverOutputs(e, ws, w);
}

// The clamp state of each section, and the pieces of the (mesh, state) pairs the configuration
// uses at this mu: by the series where it converges fast enough, else directly.
COMBABC_KERNEL void ContinuousCondensation::EvaluatePieces(std::span<const std::uint8_t> clamps,
                                                           Complex mu,
                                                           ContinuousWorkspace& ws,
                                                           Evaluated& e) const {
  const int ns = layout_->num_sections();
  ws.state.resize(ns);
  const std::size_t num_states = states_.size();
  const std::size_t num_kind_states = sections_.size();
  e.state_needed.assign(num_states, 0);
  e.kind_needed.assign(num_kind_states, 0);
  if (e.piece.size() < num_states) e.piece.resize(num_states);
  if (e.section.size() < num_kind_states) e.section.resize(num_kind_states);
  const ClampPattern pattern(clamps, ns);
  for (int s = 0; s < ns; ++s) {
    const int state = pattern.State(s);
    ws.state[s] = state;
    e.state_needed[static_cast<std::size_t>(mesh_kind_[s]) * 4 + state] = 1;
    e.kind_needed[static_cast<std::size_t>(kind_[s]) * 4 + state] = 1;
  }
  for (std::size_t index = 0; index < num_states; ++index) {
    if (!e.state_needed[index]) continue;
    const int mesh = static_cast<int>(index / 4);
    const int state = static_cast<int>(index % 4);
    const int terms = TermsFor(std::abs(mu) / states_[index].lambda_bound);
    if (terms >= 0) {
      EvaluateSeries(mesh, state, terms, mu, &e);
    } else {
      EvaluateDirect(mesh, state, mu, &e);
    }
  }
}

// The free dofs of each cross-section (SectionLayout::FreeDofs: a node on edge A (B) is fixed when
// either adjoining section fixes it; the short edges fix the first and last). Row c gets the right
// block of section c - 1 and the left block of section c (lower triangles), the loads of both and
// of its own cross-section; section c couples rows c and c + 1.
COMBABC_KERNEL void ContinuousCondensation::Assemble(std::span<const std::uint8_t> clamps,
                                                     const Evaluated& e,
                                                     ContinuousWorkspace& ws) const {
  const int ns = layout_->num_sections();
  const int nc = layout_->nc();
  const int num_cases = layout_->num_cases();
  const int rows = ws.num_rows;
  const ClampPattern pattern(clamps, ns);
  for (int c = 0; c < rows; ++c) ws.free[c] = &layout_->FreeDofs(c, pattern);
  const auto piece_of = [&](int s) -> const Complex* {
    return e.piece[static_cast<std::size_t>(mesh_kind_[s]) * 4 + ws.state[s]].data();
  };
  // Section s's load of case k (2 nc, [left; right]) when that load reaches its interior, else
  // an empty segment.
  const auto load_of = [&](int s, int k) {
    const std::size_t index = KindIndex(s, ws.state[s]);
    const SectionData& sec = sections_[index];
    const int l = sec.LoadedIndex(k);
    return e.section[index].segment(l >= 0 ? sec.loaded_start[l] : 0, l >= 0 ? 2 * nc : 0);
  };
  const Index right_block = LowerStart(nc);  // = nc (nc + 1) / 2
  const Index coupling_block = 2 * right_block;
  for (int c = 0; c < rows; ++c) {
    const std::vector<int>& f = *ws.free[c];
    const Index n = ws.RowSize(c);
    const Complex* left = c > 0 ? piece_of(c - 1) + right_block : nullptr;
    const Complex* right = c < ns ? piece_of(c) : nullptr;
    const Complex* only = left != nullptr ? left : right;  // the plate's end cross-sections
    COMBABC_CHECK(only != nullptr);  // a cross-section has a section on at least one side
    double* ar = ws.diagonal[c].re.data();
    double* ai = ws.diagonal[c].im.data();
    double max2 = 0.0;
    for (Index j = 0; j < n; ++j) {
      const Index start = LowerStart(f[j]) - f[j];
      for (Index i = j; i < n; ++i) {
        const Complex v = left != nullptr && right != nullptr
                              ? left[start + f[i]] + right[start + f[i]]
                              : only[start + f[i]];
        ar[j * n + i] = v.real();
        ai[j * n + i] = v.imag();
        // Not std::norm: without -ffast-math libstdc++ computes it as |v|^2 through hypot.
        max2 = std::max(max2, v.real() * v.real() + v.imag() * v.imag());
      }
    }
    ws.diagonal_max2[c] = max2;
    for (int k = 0; k < num_cases; ++k) {
      const auto load_left = c > 0 ? load_of(c - 1, k) : load_of(0, -1);
      const auto load_right = c < ns ? load_of(c, k) : load_of(0, -1);
      for (Index j = 0; j < n; ++j) {
        Complex v = boundary_load_[c](f[j], k);
        if (load_left.size() > 0) v += load_left(nc + f[j]);
        if (load_right.size() > 0) v += load_right(f[j]);
        ws.rhs[c].re[static_cast<std::size_t>(k) * nc + j] = v.real();
        ws.rhs[c].im[static_cast<std::size_t>(k) * nc + j] = v.imag();
      }
    }
    if (c < ns) {
      const std::vector<int>& g = *ws.free[c + 1];
      const Complex* coupling = right + coupling_block;  // nc x nc by columns
      for (Index l = 0; l < ws.RowSize(c + 1); ++l) {
        const Complex* column = coupling + Index{g[l]} * nc;
        for (Index k = 0; k < n; ++k) {
          ws.coupling[c].re[l * n + k] = column[f[k]].real();
          ws.coupling[c].im[l * n + k] = column[f[k]].imag();
        }
      }
    }
  }
}

// Every case's outputs in section s from its two end cross-sections: its offsets (when its load
// reaches the interior) plus the output map's rows of its set times its end values.
COMBABC_KERNEL void ContinuousCondensation::RecoverOutputs(
    const Evaluated& e, ContinuousWorkspace& ws, std::span<std::complex<double>> w) const {
  const int nc = layout_->nc();
  const OutputSets& sets = layout_->sets();
  for (int s = 0; s < layout_->num_sections(); ++s) {
    const OutputLayout& layout = layout_->SectionOutputs(s);
    if (layout.map_rows() == 0) continue;
    const std::size_t index = KindIndex(s, ws.state[s]);
    const SectionData& sec = sections_[index];
    const Eigen::VectorXcd& section = e.section[index];
    for (int k = 0; k < sets.num_cases(); ++k) {
      const int set = sets.set_of_case[k];
      const std::vector<int>& positions = layout.positions[set];
      const auto n_out = static_cast<Eigen::Index>(positions.size());
      if (n_out == 0) continue;
      auto ends = ws.ends.head(2 * nc);
      ends.setZero();
      for (int side = 0; side < 2; ++side) {
        const std::vector<int>& f = *ws.free[s + side];
        for (Index j = 0; j < ws.RowSize(s + side); ++j) {
          ends(Index{side} * nc + f[j]) = {ws.u[s + side].re[static_cast<std::size_t>(k) * nc + j],
                                           ws.u[s + side].im[static_cast<std::size_t>(k) * nc + j]};
        }
      }
      if (ws.values.size() < n_out) ws.values.resize(n_out);
      auto values = ws.values.head(n_out);
      const int l = sec.LoadedIndex(k);
      if (l >= 0) {
        values = section.segment(sec.loaded_start[l] + 2 * static_cast<Eigen::Index>(nc), n_out);
      } else {
        values.setZero();
      }
      const Eigen::Map<const Eigen::MatrixXcd, 0, Eigen::OuterStride<>> map(
          section.data() + layout.map_begin[set],
          n_out,
          2 * static_cast<Eigen::Index>(nc),
          Eigen::OuterStride<>(layout.map_rows()));
      values.noalias() += map * ends;
      std::complex<double>* out = w.data() + sets.first_output[k];
      for (Eigen::Index o = 0; o < n_out; ++o) out[positions[o]] = values(o);
    }
  }
}

}  // namespace combabc::plate
