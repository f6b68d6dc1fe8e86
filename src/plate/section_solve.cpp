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
#include <algorithm>
#include <cmath>
#include <vector>

#include "combabc/core/check.hpp"
#include "section_condensation.hpp"

namespace combabc::plate {
namespace {

constexpr double kPivotTol = 1e-13;     // |d_j| below this times max |a_ij| counts as breakdown
constexpr double kResidualTol = 1e-10;  // relative residual accepted from the LDL^T path

// In place A = L D L^T (unit lower L below the diagonal, D on it), no pivoting and no conjugation.
// Reads only the lower triangle of A. Right-looking: each step is a rank-1 update of the trailing
// lower triangle, column by column (contiguous axpys, no small gemv calls).
bool FactorLdlt(Eigen::Ref<Eigen::MatrixXcd> a) {
  const Eigen::Index n = a.rows();
  // Squared moduli: no hypot calls on the hot path.
  double scale2 = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    scale2 = std::max(scale2, a.col(j).tail(n - j).cwiseAbs2().maxCoeff());
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    const std::complex<double> d = a(j, j);
    if (!(std::norm(d) > kPivotTol * kPivotTol * scale2)) return false;
    const std::complex<double> inverse = std::conj(d) / std::norm(d);
    // a(k:n, k) -= a(k:n, j) l_kj with l_kj = a(k, j) / d, for the trailing columns k > j.
    for (Eigen::Index k = j + 1; k < n; ++k) {
      const std::complex<double> l = a(k, j) * inverse;
      a.col(k).segment(k, n - k) -= l * a.col(j).segment(k, n - k);
    }
    a.col(j).tail(n - j - 1) *= inverse;
  }
  return true;
}

struct Workspace {
  int nc = -1;
  int rows = -1;
  std::vector<Eigen::MatrixXcd> factor;    // pivot blocks, LDL^T in place
  std::vector<Eigen::MatrixXcd> diagonal;  // assembled diagonal blocks (for the residual)
  // Coupling U_i between rows i and i + 1 as P_i Q_i^T (n_i x r_i and n_{i+1} x r_i).
  std::vector<Eigen::MatrixXcd> p;
  std::vector<Eigen::MatrixXcd> q;
  std::vector<Eigen::MatrixXcd> y;  // Y_i = L_i^{-1} P_i
  std::vector<Eigen::Index> rank;
  std::vector<Eigen::VectorXcd> rhs;
  std::vector<Eigen::VectorXcd> z;
  std::vector<Eigen::VectorXcd> u;
  std::vector<std::vector<int>> free;
  std::vector<std::vector<int>> free_shifted;  // free + nc: the right half of a piece
  Eigen::MatrixXcd v;                          // D^{-1} Y
  Eigen::MatrixXcd s;                          // Y^T D^{-1} Y
  Eigen::MatrixXcd t;                          // Q S
  Eigen::VectorXcd tmp;
  Eigen::VectorXcd small;
  Eigen::VectorXcd ends;
  Eigen::VectorXcd values;

  void Reserve(int nc_, int rows_) {
    if (nc_ == nc && rows_ <= rows) return;
    nc = nc_;
    rows = std::max(rows_, rows);
    factor.assign(rows, Eigen::MatrixXcd(nc, nc));
    diagonal.assign(rows, Eigen::MatrixXcd(nc, nc));
    p.assign(rows, Eigen::MatrixXcd(nc, nc));
    q.assign(rows, Eigen::MatrixXcd(nc, nc));
    y.assign(rows, Eigen::MatrixXcd(nc, nc));
    rank.assign(rows, 0);
    rhs.assign(rows, Eigen::VectorXcd(nc));
    z.assign(rows, Eigen::VectorXcd(nc));
    u.assign(rows + 2, Eigen::VectorXcd(nc));
    free.assign(rows, {});
    free_shifted.assign(rows, {});
    v.resize(nc, nc);
    s.resize(nc, nc);
    t.resize(nc, nc);
    tmp.resize(nc);
    small.resize(nc);
    ends.resize(2 * nc);
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
  if (ws.values.size() < static_cast<Eigen::Index>(w.size()))
    ws.values.resize(static_cast<Eigen::Index>(w.size()));
  // Free dofs of each row: a node on edge A (B) is fixed when either adjoining section fixes it.
  for (int i = 0; i < rows; ++i) {
    const int x = (i + 1) * group_size_;
    const bool a = clamps[x - 1] != 0 || clamps[x] != 0;
    const bool b = clamps[ns + x - 1] != 0 || clamps[ns + x] != 0;
    FreeDofs(x, a, b, &ws.free[i]);
    ws.free_shifted[i] = ws.free[i];
    for (int& d : ws.free_shifted[i]) d += nc;
  }
  // Assemble: row i gets the right block of group i and the left block of group i + 1; the
  // coupling of rows i and i + 1 is group i + 1's, in its factored form.
  for (int i = 0; i < rows; ++i) {
    const Piece& left = GroupPieceOf(i, clamps);
    const Piece& right = GroupPieceOf(i + 1, clamps);
    const std::vector<int>& f = ws.free[i];
    const std::vector<int>& from_left = left.left_size == 0 ? f : ws.free_shifted[i];
    const Eigen::Index n = static_cast<Eigen::Index>(f.size());
    ws.diagonal[i].topLeftCorner(n, n) = left.condensed(from_left, from_left);
    ws.diagonal[i].topLeftCorner(n, n) += right.condensed(f, f);
    ws.rhs[i].head(n) = left.load(from_left);
    ws.rhs[i].head(n) += right.load(f);
    ws.rhs[i].head(n) += boundary_load_[(i + 1) * group_size_](f);
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      const Eigen::Index r = right.coupling_left.cols();
      ws.rank[i] = r;
      ws.p[i].topLeftCorner(n, r) = right.coupling_left(f, Eigen::all);
      ws.q[i].topLeftCorner(m, r) = right.coupling_right(ws.free[i + 1], Eigen::all);
    }
  }
  // Block LDL^T elimination: F_0 = A_0; F_{i+1} = A_{i+1} - U_i^T F_i^{-1} U_i; z = L^{-1} r'.
  // With U_i = P_i Q_i^T and Y_i = L_i^{-1} P_i: U_i^T F_i^{-1} U_i = Q_i (Y_i^T D_i^{-1} Y_i)
  // Q_i^T.
  bool ok = !always_pivot_;
  for (int i = 0; i < rows && ok; ++i) {
    const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
    auto f = ws.factor[i].topLeftCorner(n, n);
    if (i == 0) {
      f = ws.diagonal[0].topLeftCorner(n, n);
      ws.z[0].head(n) = ws.rhs[0].head(n);
    }
    ok = FactorLdlt(f);
    if (!ok) break;
    auto z = ws.z[i].head(n);
    f.triangularView<Eigen::UnitLower>().solveInPlace(z);
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      const Eigen::Index r = ws.rank[i];
      auto yi = ws.y[i].topLeftCorner(n, r);
      yi = ws.p[i].topLeftCorner(n, r);
      f.triangularView<Eigen::UnitLower>().solveInPlace(yi);
      auto v = ws.v.topLeftCorner(n, r);
      for (Eigen::Index k = 0; k < n; ++k) {
        v.row(k) = (std::conj(f(k, k)) / std::norm(f(k, k))) * yi.row(k);
      }
      auto sm = ws.s.topLeftCorner(r, r);
      sm.noalias() = yi.transpose() * v;
      auto qi = ws.q[i].topLeftCorner(m, r);
      auto t = ws.t.topLeftCorner(m, r);
      t.noalias() = qi * sm;
      auto next = ws.factor[i + 1].topLeftCorner(m, m);
      // The Schur complement is symmetric and FactorLdlt reads only the lower triangle.
      next = ws.diagonal[i + 1].topLeftCorner(m, m);
      next.triangularView<Eigen::Lower>() -= t * qi.transpose();
      auto c = ws.small.head(r);
      c.noalias() = v.transpose() * z;
      ws.z[i + 1].head(m) = ws.rhs[i + 1].head(m);
      ws.z[i + 1].head(m).noalias() -= qi * c;
    }
  }
  // Back substitution: u_i = L_i^{-T} D_i^{-1} (z_i - Y_i Q_i^T u_{i+1}).
  for (int i = rows - 1; i >= 0 && ok; --i) {
    const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
    auto f = ws.factor[i].topLeftCorner(n, n);
    auto y = ws.tmp.head(n);
    y = ws.z[i].head(n);
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      const Eigen::Index r = ws.rank[i];
      auto c = ws.small.head(r);
      c.noalias() = ws.q[i].topLeftCorner(m, r).transpose() * ws.u[i + 1].head(m);
      y.noalias() -= ws.y[i].topLeftCorner(n, r) * c;
    }
    for (Eigen::Index k = 0; k < n; ++k) y(k) *= std::conj(f(k, k)) / std::norm(f(k, k));
    f.transpose().triangularView<Eigen::UnitUpper>().solveInPlace(y);
    ws.u[i].head(n) = y;
  }
  // Residual of the assembled system; the unpivoted path must earn its result.
  if (ok) {
    double residual = 0.0;
    double scale = 0.0;
    for (int i = 0; i < rows; ++i) {
      const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
      auto r = ws.tmp.head(n);
      r.noalias() = ws.diagonal[i].topLeftCorner(n, n) * ws.u[i].head(n);
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
      const double a2 = ws.diagonal[i].topLeftCorner(n, n).cwiseAbs2().maxCoeff();
      scale = std::max(scale,
                       std::sqrt(ws.rhs[i].head(n).cwiseAbs2().maxCoeff()) +
                           std::sqrt(a2 * ws.u[i].head(n).cwiseAbs2().maxCoeff()));
    }
    ok = std::sqrt(residual) <= kResidualTol * scale;
  }
  if (!ok) {
    // Fallback: dense partial-pivoting LU of the whole condensed system, with the couplings
    // taken from the pieces as computed (not their factored form).
    std::vector<Eigen::Index> offset(rows + 1, 0);
    for (int i = 0; i < rows; ++i)
      offset[i + 1] = offset[i] + static_cast<Eigen::Index>(ws.free[i].size());
    Eigen::MatrixXcd big = Eigen::MatrixXcd::Zero(offset[rows], offset[rows]);
    Eigen::VectorXcd big_rhs(offset[rows]);
    for (int i = 0; i < rows; ++i) {
      const Eigen::Index n = offset[i + 1] - offset[i];
      big.block(offset[i], offset[i], n, n) = ws.diagonal[i].topLeftCorner(n, n);
      big_rhs.segment(offset[i], n) = ws.rhs[i].head(n);
      if (i + 1 < rows) {
        const Eigen::Index m = offset[i + 2] - offset[i + 1];
        const Piece& right = GroupPieceOf(i + 1, clamps);
        const Eigen::MatrixXcd coupling = right.condensed(ws.free[i], ws.free_shifted[i + 1]);
        big.block(offset[i], offset[i + 1], n, m) = coupling;
        big.block(offset[i + 1], offset[i], m, n) = coupling.transpose();
      }
    }
    const Eigen::VectorXcd solution = big.partialPivLu().solve(big_rhs);
    for (int i = 0; i < rows; ++i)
      ws.u[i].head(offset[i + 1] - offset[i]) =
          solution.segment(offset[i], offset[i + 1] - offset[i]);
  }
  // Outputs of group g from its kept end cross-sections (rows g - 1 and g).
  for (int g = 0; g < ng; ++g) {
    const std::vector<int>& outputs = group_outputs_[g];
    if (outputs.empty()) continue;
    const Piece& piece = GroupPieceOf(g, clamps);
    auto ends = ws.ends.head(piece.left_size + piece.right_size);
    ends.setZero();
    if (piece.left_size > 0)
      ends(ws.free[g - 1]) = ws.u[g - 1].head(static_cast<Eigen::Index>(ws.free[g - 1].size()));
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
