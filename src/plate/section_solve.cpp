// The per-configuration solve of the condensed system (docs/model.md, "Section condensation").
// The cached pieces are already Jacobi-scaled (SectionCondensation's constructor), so the
// unknowns here are scaled cross-section dofs and the output maps take them as they are.
//
// The unknowns are the free dofs of the inner group boundaries; the matrix is block tridiagonal
// and complex symmetric (K(1 + i eta) - omega^2 M is symmetric, not Hermitian). It is solved by
// block elimination with an unpivoted complex-symmetric LDL^T of each pivot block (about half the
// work of LU, and symmetric Schur complements). Unpivoted LDL^T is stable when the real part is
// positive definite (the default: 5 Hz is below every resonance), but not in general, so every
// solve is followed by a residual check, and a dense partial-pivoting LU of the whole condensed
// system is the fallback.
//
// Performance (docs/benchmarks.md): the coupling between neighbouring rows is a group's
// end-to-end block, numerically of low rank (SectionCondensation's constructor factors it as
// P Q^T), so a Schur complement costs O(n^2 r) rather than O(n^3); the triangular solves with
// P and the right-hand side ride along inside the factorization's matrix-vector products; the
// workspace is per thread and reused, and the cached blocks are read as contiguous columns.
#include <algorithm>
#include <cmath>
#include <vector>

#include "block_ldlt.hpp"
#include "combabc/core/check.hpp"
#include "section_condensation.hpp"

namespace combabc::plate {
namespace {

struct Workspace {
  int nc = -1;
  int rows = -1;
  // Pivot blocks F_i, LDL^T in place, with P_i^T and the right-hand side carried below them.
  std::vector<Eigen::MatrixXcd> factor;
  std::vector<Eigen::MatrixXcd> diagonal;  // assembled diagonal blocks (for the residual)
  // Coupling U_i between rows i and i + 1 as P_i Q_i^T (n_i x r_i and n_{i+1} x r_i).
  std::vector<Eigen::MatrixXcd> p;
  std::vector<Eigen::MatrixXcd> q;
  std::vector<Eigen::Index> rank;
  std::vector<Eigen::VectorXcd> rhs;
  std::vector<Eigen::VectorXcd> u;
  std::vector<std::vector<int>> free;
  Eigen::MatrixXcd v;  // D V
  Eigen::MatrixXcd s;  // S = V^T D V
  Eigen::MatrixXcd t;  // Q S
  Eigen::VectorXcd tmp;
  Eigen::VectorXcd small;
  Eigen::VectorXcd ends;
  Eigen::VectorXcd values;

  void Reserve(int nc_, int rows_) {
    if (nc_ == nc && rows_ <= rows) return;
    nc = nc_;
    rows = std::max(rows_, rows);
    factor.assign(rows, Eigen::MatrixXcd(2 * nc + 1, nc));
    diagonal.assign(rows, Eigen::MatrixXcd(nc, nc));
    p.assign(rows, Eigen::MatrixXcd(nc, nc));
    q.assign(rows, Eigen::MatrixXcd(nc, nc));
    rank.assign(rows, 0);
    rhs.assign(rows, Eigen::VectorXcd(nc));
    u.assign(rows + 2, Eigen::VectorXcd(nc));
    free.assign(rows, {});
    v.resize(nc, nc);
    s.resize(nc, nc);
    t.resize(nc, nc);
    tmp.resize(nc);
    small.resize(nc);
    ends.resize(2 * static_cast<Eigen::Index>(nc));
  }
};

}  // namespace

void SectionCondensation::Solve(std::span<const std::uint8_t> clamps,
                                std::span<std::complex<double>> w) const {
  const int ns = num_sections_;
  const int ng = ns / group_size_;
  const int nc = nc_;
  const int rows = ng - 1;  // inner group boundaries c = 1..ng-1 are rows c - 1
  thread_local Workspace ws;
  ws.Reserve(nc, std::max(rows, 1));
  if (ws.values.size() < static_cast<Eigen::Index>(w.size())) {
    ws.values.resize(static_cast<Eigen::Index>(w.size()));
  }
  // Free dofs of each row: a node on edge A (B) is fixed when either adjoining section fixes it.
  for (int i = 0; i < rows; ++i) {
    const int x = (i + 1) * group_size_;
    const bool a = clamps[x - 1] != 0 || clamps[x] != 0;
    const bool b = clamps[ns + x - 1] != 0 || clamps[ns + x] != 0;
    FreeDofs(x, a, b, &ws.free[i]);
  }
  // Assemble: row i gets the right block of group i and the left block of group i + 1 (lower
  // triangles only: the blocks are symmetric); the coupling of rows i and i + 1 is group
  // i + 1's, in its factored form.
  for (int i = 0; i < rows; ++i) {
    const Piece& left = GroupPieceOf(i, clamps);
    const Piece& right = GroupPieceOf(i + 1, clamps);
    const std::vector<int>& f = ws.free[i];
    const Eigen::Index n = static_cast<Eigen::Index>(f.size());
    auto a = ws.diagonal[i].topLeftCorner(n, n);
    for (Eigen::Index c = 0; c < n; ++c) {
      const std::complex<double>* lc =
          left.right_block.data() + static_cast<Eigen::Index>(f[c]) * nc;
      const std::complex<double>* rc =
          right.left_block.data() + static_cast<Eigen::Index>(f[c]) * nc;
      for (Eigen::Index r = c; r < n; ++r) a(r, c) = lc[f[r]] + rc[f[r]];
    }
    ws.rhs[i].head(n) = left.load.tail(nc)(f);
    ws.rhs[i].head(n) += right.load.head(nc)(f);
    const auto boundary = static_cast<std::size_t>(i + 1) * static_cast<std::size_t>(group_size_);
    ws.rhs[i].head(n) += boundary_load_[boundary](f);
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      const Eigen::Index r = right.coupling_left.cols();
      ws.rank[i] = r;
      ws.p[i].topLeftCorner(n, r) = right.coupling_left(f, Eigen::all);
      ws.q[i].topLeftCorner(m, r) = right.coupling_right(ws.free[i + 1], Eigen::all);
    }
  }
  // Block LDL^T elimination: F_0 = A_0; F_{i+1} = A_{i+1} - U_i^T F_i^{-1} U_i. With
  // U_i = P_i Q_i^T, V_i = D_i^{-1} L_i^{-1} P_i (from FactorLdlt's carried rows) and
  // S_i = V_i^T D_i V_i: U_i^T F_i^{-1} U_i = Q_i S_i Q_i^T. The right-hand side is eliminated
  // alongside: row i's carried last row becomes w_i = D_i^{-1} L_i^{-1} r'_i, and
  // r'_{i+1} = r_{i+1} - Q_i V_i^T D_i w_i.
  const auto carried = [&](int i) { return i + 1 < rows ? ws.rank[i] : Eigen::Index{0}; };
  bool ok = !always_pivot_;
  for (int i = 0; i < rows && ok; ++i) {
    const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
    const Eigen::Index r = carried(i);
    auto ext = ws.factor[i].topLeftCorner(n + r + 1, n);
    if (i == 0) {
      ext.topRows(n).triangularView<Eigen::Lower>() = ws.diagonal[0].topLeftCorner(n, n);
      ext.row(n + r) = ws.rhs[0].head(n).transpose();
    }
    if (r > 0) ext.middleRows(n, r) = ws.p[i].topLeftCorner(n, r).transpose();
    ok = FactorLdlt(ext, ws.tmp.head(n));
    if (!ok) break;
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      const Eigen::Index rn = carried(i + 1);
      const auto vt = ext.middleRows(n, r);  // V_i^T
      auto dv = ws.v.topLeftCorner(n, r);    // D_i V_i
      dv.noalias() = ext.diagonal().asDiagonal() * vt.transpose();
      auto sm = ws.s.topLeftCorner(r, r);
      sm.noalias() = vt.lazyProduct(dv);
      auto qi = ws.q[i].topLeftCorner(m, r);
      auto t = ws.t.topLeftCorner(m, r);
      t.noalias() = qi.lazyProduct(sm);
      auto next = ws.factor[i + 1].topLeftCorner(m + rn + 1, m);
      // The Schur complement is symmetric and FactorLdlt reads only the lower triangle.
      next.topRows(m).triangularView<Eigen::Lower>() = ws.diagonal[i + 1].topLeftCorner(m, m);
      next.topRows(m).triangularView<Eigen::Lower>() -= t * qi.transpose();
      auto c = ws.small.head(r);
      c.noalias() = dv.transpose() * ext.row(n + r).transpose();
      auto b = ws.tmp.head(m);
      b = ws.rhs[i + 1].head(m);
      b.noalias() -= qi * c;
      next.row(m + rn) = b.transpose();
    }
  }
  // Back substitution: u_i = L_i^{-T} (w_i - V_i Q_i^T u_{i+1}).
  for (int i = rows - 1; i >= 0 && ok; --i) {
    const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
    const Eigen::Index r = carried(i);
    const auto ext = ws.factor[i].topLeftCorner(n + r + 1, n);
    auto y = ws.tmp.head(n);
    y = ext.row(n + r).transpose();
    if (r > 0) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      auto c = ws.small.head(r);
      c.noalias() = ws.q[i].topLeftCorner(m, r).transpose() * ws.u[i + 1].head(m);
      y.noalias() -= ext.middleRows(n, r).transpose() * c;
    }
    ext.topRows(n).transpose().triangularView<Eigen::UnitUpper>().solveInPlace(y);
    ws.u[i].head(n) = y;
  }
  // Residual of the assembled system; the unpivoted path must earn its result.
  if (ok) {
    double residual = 0.0;
    double scale = 0.0;
    for (int i = 0; i < rows; ++i) {
      const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
      auto r = ws.tmp.head(n);
      const auto a = ws.diagonal[i].topLeftCorner(n, n);  // lower triangle of a symmetric block
      r.noalias() = a.triangularView<Eigen::Lower>() * ws.u[i].head(n);
      r.noalias() += a.triangularView<Eigen::StrictlyLower>().transpose() * ws.u[i].head(n);
      r -= ws.rhs[i].head(n);
      if (i + 1 < rows) {
        const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
        const Eigen::Index k = ws.rank[i];
        auto c = ws.small.head(k);
        c.noalias() = ws.q[i].topLeftCorner(m, k).transpose() * ws.u[i + 1].head(m);
        r.noalias() += ws.p[i].topLeftCorner(n, k) * c;
      }
      if (i > 0) {
        const Eigen::Index p = static_cast<Eigen::Index>(ws.free[i - 1].size());
        const Eigen::Index k = ws.rank[i - 1];
        auto c = ws.small.head(k);
        c.noalias() = ws.p[i - 1].topLeftCorner(p, k).transpose() * ws.u[i - 1].head(p);
        r.noalias() += ws.q[i - 1].topLeftCorner(n, k) * c;
      }
      // Squared moduli (max |.|^2) to keep hypot off the hot path.
      residual = std::max(residual, r.cwiseAbs2().maxCoeff());
      double a2 = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        a2 = std::max(a2, a.col(j).tail(n - j).cwiseAbs2().maxCoeff());
      }
      scale = std::max(scale,
                       std::sqrt(ws.rhs[i].head(n).cwiseAbs2().maxCoeff()) +
                           std::sqrt(a2 * ws.u[i].head(n).cwiseAbs2().maxCoeff()));
    }
    ok = std::sqrt(residual) <= kResidualTol * scale;
  }
  if (!ok) {
    // Fallback: dense partial-pivoting LU of the whole condensed system.
    std::vector<Eigen::Index> offset(rows + 1, 0);
    for (int i = 0; i < rows; ++i) {
      offset[i + 1] = offset[i] + static_cast<Eigen::Index>(ws.free[i].size());
    }
    Eigen::MatrixXcd big = Eigen::MatrixXcd::Zero(offset[rows], offset[rows]);
    Eigen::VectorXcd big_rhs(offset[rows]);
    for (int i = 0; i < rows; ++i) {
      const Eigen::Index n = offset[i + 1] - offset[i];
      const auto a = ws.diagonal[i].topLeftCorner(n, n);
      auto block = big.block(offset[i], offset[i], n, n);
      block.triangularView<Eigen::Lower>() = a;
      block.triangularView<Eigen::StrictlyUpper>() = a.transpose();
      big_rhs.segment(offset[i], n) = ws.rhs[i].head(n);
      if (i + 1 < rows) {
        const Eigen::Index m = offset[i + 2] - offset[i + 1];
        const Eigen::Index r = ws.rank[i];
        const Eigen::MatrixXcd coupling =
            ws.p[i].topLeftCorner(n, r) * ws.q[i].topLeftCorner(m, r).transpose();
        big.block(offset[i], offset[i + 1], n, m) = coupling;
        big.block(offset[i + 1], offset[i], m, n) = coupling.transpose();
      }
    }
    const Eigen::VectorXcd solution = big.partialPivLu().solve(big_rhs);
    for (int i = 0; i < rows; ++i) {
      ws.u[i].head(offset[i + 1] - offset[i]) =
          solution.segment(offset[i], offset[i + 1] - offset[i]);
    }
  }
  // Outputs of group g from its kept end cross-sections (rows g - 1 and g).
  for (int g = 0; g < ng; ++g) {
    const std::vector<int>& outputs = group_outputs_[g];
    if (outputs.empty()) continue;
    const Piece& piece = GroupPieceOf(g, clamps);
    auto ends = ws.ends.head(piece.left_size + piece.right_size);
    ends.setZero();
    if (piece.left_size > 0) {
      ends(ws.free[g - 1]) = ws.u[g - 1].head(static_cast<Eigen::Index>(ws.free[g - 1].size()));
    }
    if (piece.right_size > 0) {
      ends.tail(nc)(ws.free[g]) = ws.u[g].head(static_cast<Eigen::Index>(ws.free[g].size()));
    }
    auto values = ws.values.head(piece.output_map.rows());
    values = piece.output_offset;
    values.noalias() += piece.output_map * ends;
    for (std::size_t k = 0; k < outputs.size(); ++k) {
      w[outputs[k]] = values(static_cast<Eigen::Index>(k));
    }
  }
}

}  // namespace combabc::plate
