#pragma once
// The dense kernel shared by the per-configuration block solves (section_solve.cpp for the
// clamp-only fast path, continuous_solve.cpp for continuous unknowns): an unpivoted
// complex-symmetric LDL^T that carries extra rows through the factorization. Inline so each solve
// keeps it inlined in its hot loop as before.
#include <algorithm>
#include <complex>

#include <Eigen/Dense>

namespace combabc::plate {

inline constexpr double kPivotTol = 1e-13;     // |d_j| below this times max |a_ij| is breakdown
inline constexpr double kResidualTol = 1e-10;  // relative residual accepted from the LDL^T path

// In place A = L D L^T (unit lower L below the diagonal, D on it), no pivoting and no conjugation,
// of the leading n x n block of the rows x n matrix `a` (rows >= n); reads only its lower
// triangle. Rows below it, B (rows - n x n), are carried along and become B L^{-T} D^{-1}: with
// B = [P^T; b^T] that is (D^{-1} L^{-1} P)^T and (D^{-1} L^{-1} b)^T, the triangular solves the
// block elimination needs, done inside the factorization's matrix-vector products.
inline bool FactorLdlt(Eigen::Ref<Eigen::MatrixXcd> a, Eigen::Ref<Eigen::VectorXcd> tmp) {
  const Eigen::Index n = a.cols();
  const Eigen::Index rows = a.rows();
  // Squared moduli: no hypot calls on the hot path.
  double scale2 = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    scale2 = std::max(scale2, a.col(j).segment(j, n - j).cwiseAbs2().maxCoeff());
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    if (j > 0) {
      tmp.head(j) = a.row(j).head(j).transpose().cwiseProduct(a.diagonal().head(j));
      a.col(j).tail(rows - j).noalias() -= a.block(j, 0, rows - j, j) * tmp.head(j);
    }
    const std::complex<double> d = a(j, j);
    if (!(std::norm(d) > kPivotTol * kPivotTol * scale2)) return false;
    const std::complex<double> inverse = std::conj(d) / std::norm(d);
    a.col(j).tail(rows - j - 1) *= inverse;
  }
  return true;
}

}  // namespace combabc::plate
