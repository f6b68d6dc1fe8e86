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
// Reads only the lower triangle of A.
bool FactorLdlt(Eigen::Ref<Eigen::MatrixXcd> a, Eigen::Ref<Eigen::VectorXcd> tmp) {
  const Eigen::Index n = a.rows();
  // Squared moduli: no hypot calls on the hot path.
  double scale2 = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    scale2 = std::max(scale2, a.col(j).tail(n - j).cwiseAbs2().maxCoeff());
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    if (j > 0) {
      tmp.head(j) = a.row(j).head(j).transpose().cwiseProduct(a.diagonal().head(j));
      a.col(j).tail(n - j).noalias() -= a.block(j, 0, n - j, j) * tmp.head(j);
    }
    const std::complex<double> d = a(j, j);
    if (!(std::norm(d) > kPivotTol * kPivotTol * scale2)) return false;
    const std::complex<double> inverse = std::conj(d) / std::norm(d);
    a.col(j).tail(n - j - 1) *= inverse;
  }
  return true;
}

struct Workspace {
  int nc = -1;
  int rows = -1;
  std::vector<Eigen::MatrixXcd> factor;    // pivot blocks, LDL^T in place
  std::vector<Eigen::MatrixXcd> diagonal;  // assembled diagonal blocks (for the residual)
  std::vector<Eigen::MatrixXcd> coupling;  // U_i between rows i and i + 1
  std::vector<Eigen::MatrixXcd> reduced;   // W_i = L_i^{-1} U_i
  std::vector<Eigen::VectorXcd> rhs;
  std::vector<Eigen::VectorXcd> z;
  std::vector<Eigen::VectorXcd> u;
  std::vector<std::vector<int>> free;
  std::vector<std::vector<int>> free_shifted;  // free + nc: the right half of a piece
  Eigen::MatrixXcd scaled;
  Eigen::VectorXcd tmp;
  Eigen::VectorXcd ends;
  Eigen::VectorXcd values;

  void Reserve(int nc_, int rows_) {
    if (nc_ == nc && rows_ <= rows) return;
    nc = nc_;
    rows = std::max(rows_, rows);
    factor.assign(rows, Eigen::MatrixXcd(nc, nc));
    diagonal.assign(rows, Eigen::MatrixXcd(nc, nc));
    coupling.assign(rows, Eigen::MatrixXcd(nc, nc));
    reduced.assign(rows, Eigen::MatrixXcd(nc, nc));
    rhs.assign(rows, Eigen::VectorXcd(nc));
    z.assign(rows, Eigen::VectorXcd(nc));
    u.assign(rows + 2, Eigen::VectorXcd(nc));
    free.assign(rows, {});
    free_shifted.assign(rows, {});
    scaled.resize(nc, nc);
    tmp.resize(nc);
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
  // Assemble: row i gets the right block of group i and the left block of group i + 1.
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
      ws.coupling[i].topLeftCorner(n, m) = right.condensed(f, ws.free_shifted[i + 1]);
    }
  }
  // Block LDL^T elimination: F_0 = A_0; F_{i+1} = A_{i+1} - W_i^T D_i^{-1} W_i; z = L^{-1} r'.
  bool ok = !always_pivot_;
  for (int i = 0; i < rows && ok; ++i) {
    const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
    auto f = ws.factor[i].topLeftCorner(n, n);
    if (i == 0) {
      f = ws.diagonal[0].topLeftCorner(n, n);
      ws.z[0].head(n) = ws.rhs[0].head(n);
    }
    ok = FactorLdlt(f, ws.tmp.head(n));
    if (!ok) break;
    auto z = ws.z[i].head(n);
    f.triangularView<Eigen::UnitLower>().solveInPlace(z);
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      auto wr = ws.reduced[i].topLeftCorner(n, m);
      wr = ws.coupling[i].topLeftCorner(n, m);
      f.triangularView<Eigen::UnitLower>().solveInPlace(wr);
      auto v = ws.scaled.topLeftCorner(n, m);
      for (Eigen::Index k = 0; k < n; ++k) {
        v.row(k) = (std::conj(f(k, k)) / std::norm(f(k, k))) * wr.row(k);
      }
      auto next = ws.factor[i + 1].topLeftCorner(m, m);
      // The Schur complement is symmetric and FactorLdlt reads only the lower triangle.
      next = ws.diagonal[i + 1].topLeftCorner(m, m);
      next.triangularView<Eigen::Lower>() -= wr.transpose() * v;
      ws.z[i + 1].head(m) = ws.rhs[i + 1].head(m);
      ws.z[i + 1].head(m).noalias() -= v.transpose() * z;
    }
  }
  // Back substitution: u_i = L_i^{-T} D_i^{-1} (z_i - W_i u_{i+1}).
  for (int i = rows - 1; i >= 0 && ok; --i) {
    const Eigen::Index n = static_cast<Eigen::Index>(ws.free[i].size());
    auto f = ws.factor[i].topLeftCorner(n, n);
    auto y = ws.tmp.head(n);
    y = ws.z[i].head(n);
    if (i + 1 < rows) {
      const Eigen::Index m = static_cast<Eigen::Index>(ws.free[i + 1].size());
      y.noalias() -= ws.reduced[i].topLeftCorner(n, m) * ws.u[i + 1].head(m);
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
        r.noalias() += ws.coupling[i].topLeftCorner(n, m) * ws.u[i + 1].head(m);
      }
      if (i > 0) {
        const Eigen::Index p = static_cast<Eigen::Index>(ws.free[i - 1].size());
        r.noalias() += ws.coupling[i - 1].topLeftCorner(p, n).transpose() * ws.u[i - 1].head(p);
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
    // Fallback: dense partial-pivoting LU of the whole condensed system.
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
        big.block(offset[i], offset[i + 1], n, m) = ws.coupling[i].topLeftCorner(n, m);
        big.block(offset[i + 1], offset[i], m, n) = ws.coupling[i].topLeftCorner(n, m).transpose();
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
