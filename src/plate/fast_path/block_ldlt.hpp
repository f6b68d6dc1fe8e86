#pragma once
// What the per-configuration block solves share (section_solve.cpp for the clamp-only fast path,
// continuous_solve.cpp for continuous unknowns), all on split real/imaginary storage: the dense
// kernels, an unpivoted complex-symmetric LDL^T that carries extra rows through the factorization
// (FactorLdltSplit) and the complex axpys the solves build their Schur updates, back
// substitutions and residuals from (SubScaled*Split); the per-thread workspace of the block rows
// (BlockWorkspace); and the phases both solves run alike on it: the residual check's frame, the
// pivoting fallback's frame and the singularity check. Inline so each solve keeps them inlined in
// its hot loops; forced inline (COMBABC_KERNEL) so that each instruction-set copy of a solve
// (kernel_targets.hpp) runs them with its own instructions. Only the two solves' files include
// this header: they are compiled without fused multiply-adds (src/CMakeLists.txt).
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "combabc/plate/assembly/plate.hpp"
#include "plate/fast_path/kernel_targets.hpp"

namespace combabc::plate {

inline constexpr double kPivotTol = 1e-13;     // |d_j| below this times max |a_ij| is breakdown
inline constexpr double kResidualTol = 1e-10;  // relative residual accepted from the LDL^T path

// Split storage: a complex matrix as two column-major arrays of doubles (real and imaginary parts,
// leading dimension ld). Plain loops over them vectorize with SSE2 alone; interleaved
// std::complex needs shuffles, and its operator* calls __muldc3 unless -ffast-math.

using Index = std::ptrdiff_t;

// A complex matrix or vector in split storage, column-major; the leading dimension is chosen per
// use.
struct Split {
  std::vector<double> re;
  std::vector<double> im;
  void Resize(Index size) {
    re.resize(static_cast<std::size_t>(size));
    im.resize(static_cast<std::size_t>(size));
  }
};

// c -= x s over `len` entries (complex axpy in split storage).
COMBABC_KERNEL void SubScaledSplit(double* __restrict cr,
                                   double* __restrict ci,
                                   const double* __restrict xr,
                                   const double* __restrict xi,
                                   double sr,
                                   double si,
                                   std::ptrdiff_t len) {
  for (std::ptrdiff_t t = 0; t < len; ++t) {
    cr[t] -= xr[t] * sr - xi[t] * si;
    ci[t] -= xr[t] * si + xi[t] * sr;
  }
}

// c -= x s + y t: two axpys in one pass over c (half the loads and stores of c).
COMBABC_KERNEL void SubScaled2Split(double* __restrict cr,
                                    double* __restrict ci,
                                    const double* __restrict xr,
                                    const double* __restrict xi,
                                    double sr,
                                    double si,
                                    const double* __restrict yr,
                                    const double* __restrict yi,
                                    double tr,
                                    double ti,
                                    std::ptrdiff_t len) {
  for (std::ptrdiff_t k = 0; k < len; ++k) {
    cr[k] -= (xr[k] * sr - xi[k] * si) + (yr[k] * tr - yi[k] * ti);
    ci[k] -= (xr[k] * si + xi[k] * sr) + (yr[k] * ti + yi[k] * tr);
  }
}

// c -= x0 s0 + x1 s1 + x2 s2 + x3 s3 (x_k at x + k ldx, s_k = (sr[k], si[k])): four axpys in one
// pass.
COMBABC_KERNEL void SubScaled4Split(double* __restrict cr,
                                    double* __restrict ci,
                                    const double* __restrict xr,
                                    const double* __restrict xi,
                                    std::ptrdiff_t ldx,
                                    const double* sr,
                                    const double* si,
                                    std::ptrdiff_t len) {
  const double s0r = sr[0], s0i = si[0], s1r = sr[1], s1i = si[1];
  const double s2r = sr[2], s2i = si[2], s3r = sr[3], s3i = si[3];
  const double* __restrict x0r = xr;
  const double* __restrict x0i = xi;
  const double* __restrict x1r = xr + ldx;
  const double* __restrict x1i = xi + ldx;
  const double* __restrict x2r = xr + 2 * ldx;
  const double* __restrict x2i = xi + 2 * ldx;
  const double* __restrict x3r = xr + 3 * ldx;
  const double* __restrict x3i = xi + 3 * ldx;
  for (std::ptrdiff_t k = 0; k < len; ++k) {
    cr[k] -= ((x0r[k] * s0r - x0i[k] * s0i) + (x1r[k] * s1r - x1i[k] * s1i)) +
             ((x2r[k] * s2r - x2i[k] * s2i) + (x3r[k] * s3r - x3i[k] * s3i));
    ci[k] -= ((x0r[k] * s0i + x0i[k] * s0r) + (x1r[k] * s1i + x1i[k] * s1r)) +
             ((x2r[k] * s2i + x2i[k] * s2r) + (x3r[k] * s3i + x3i[k] * s3r));
  }
}

// c -= sum_{k < count} x_k s_k (x_k at x + k ldx, s_k = (sr[k], si[k])): four terms per pass
// over c, then two, then one.
COMBABC_KERNEL void SubScaledManySplit(double* cr,
                                       double* ci,
                                       const double* xr,
                                       const double* xi,
                                       std::ptrdiff_t ldx,
                                       const double* sr,
                                       const double* si,
                                       std::ptrdiff_t count,
                                       std::ptrdiff_t len) {
  std::ptrdiff_t k = 0;
  for (; k + 3 < count; k += 4) {
    SubScaled4Split(cr, ci, xr + k * ldx, xi + k * ldx, ldx, sr + k, si + k, len);
  }
  if (k + 1 < count) {
    SubScaled2Split(cr,
                    ci,
                    xr + k * ldx,
                    xi + k * ldx,
                    sr[k],
                    si[k],
                    xr + (k + 1) * ldx,
                    xi + (k + 1) * ldx,
                    sr[k + 1],
                    si[k + 1],
                    len);
    k += 2;
  }
  if (k < count) SubScaledSplit(cr, ci, xr + k * ldx, xi + k * ldx, sr[k], si[k], len);
}

// Complex dot product sum_k x_k y_k (no conjugation) of split vectors.
COMBABC_KERNEL void DotSplit(const double* xr,
                             const double* xi,
                             const double* yr,
                             const double* yi,
                             std::ptrdiff_t len,
                             double* out_r,
                             double* out_i) {
  // Two partial sums per part (even and odd k): one would chain every add on the previous
  // one's latency.
  double sr[2] = {0.0, 0.0};
  double si[2] = {0.0, 0.0};
  std::ptrdiff_t k = 0;
  for (; k + 1 < len; k += 2) {
    for (int q = 0; q < 2; ++q) {
      sr[q] += xr[k + q] * yr[k + q] - xi[k + q] * yi[k + q];
      si[q] += xr[k + q] * yi[k + q] + xi[k + q] * yr[k + q];
    }
  }
  if (k < len) {
    sr[0] += xr[k] * yr[k] - xi[k] * yi[k];
    si[0] += xr[k] * yi[k] + xi[k] * yr[k];
  }
  *out_r = sr[0] + sr[1];
  *out_i = si[0] + si[1];
}

// DotSplit of x with W vectors at once, stored side by side within each entry (vector c of entry
// k at y + k ldy + c): out[c] = sum_k x_k y_kc. Each vector takes exactly DotSplit's operations
// (even and odd k summed apart, then added), so it gets DotSplit's bits; the W vectors are
// independent lanes (W doubles: one AVX2 register), where one vector alone is a latency chain.
template <int W>
COMBABC_KERNEL void DotSplitLanes(const double* __restrict xr,
                                  const double* __restrict xi,
                                  const double* __restrict yr,
                                  const double* __restrict yi,
                                  std::ptrdiff_t ldy,
                                  std::ptrdiff_t len,
                                  double* __restrict out_r,
                                  double* __restrict out_i) {
  double sr0[W] = {};
  double sr1[W] = {};
  double si0[W] = {};
  double si1[W] = {};
  std::ptrdiff_t k = 0;
  for (; k + 1 < len; k += 2) {
    const double ar = xr[k];
    const double ai = xi[k];
    const double br = xr[k + 1];
    const double bi = xi[k + 1];
    const double* __restrict y0r = yr + k * ldy;
    const double* __restrict y0i = yi + k * ldy;
    const double* __restrict y1r = yr + (k + 1) * ldy;
    const double* __restrict y1i = yi + (k + 1) * ldy;
    for (int c = 0; c < W; ++c) {
      sr0[c] += ar * y0r[c] - ai * y0i[c];
      si0[c] += ar * y0i[c] + ai * y0r[c];
      sr1[c] += br * y1r[c] - bi * y1i[c];
      si1[c] += br * y1i[c] + bi * y1r[c];
    }
  }
  if (k < len) {
    const double ar = xr[k];
    const double ai = xi[k];
    const double* __restrict y0r = yr + k * ldy;
    const double* __restrict y0i = yi + k * ldy;
    for (int c = 0; c < W; ++c) {
      sr0[c] += ar * y0r[c] - ai * y0i[c];
      si0[c] += ar * y0i[c] + ai * y0r[c];
    }
  }
  for (int c = 0; c < W; ++c) {
    out_r[c] = sr0[c] + sr1[c];
    out_i[c] = si0[c] + si1[c];
  }
}

// DotSplitLanes for any number of vectors (`cases`, stored side by side: ldy = cases): four
// lanes at a time, then two, then one.
COMBABC_KERNEL void DotSplitCases(const double* xr,
                                  const double* xi,
                                  const double* yr,
                                  const double* yi,
                                  std::ptrdiff_t len,
                                  std::ptrdiff_t cases,
                                  double* out_r,
                                  double* out_i) {
  std::ptrdiff_t c = 0;
  for (; c + 3 < cases; c += 4) {
    DotSplitLanes<4>(xr, xi, yr + c, yi + c, cases, len, out_r + c, out_i + c);
  }
  if (c + 1 < cases) {
    DotSplitLanes<2>(xr, xi, yr + c, yi + c, cases, len, out_r + c, out_i + c);
    c += 2;
  }
  if (c < cases) DotSplitLanes<1>(xr, xi, yr + c, yi + c, cases, len, out_r + c, out_i + c);
}

// y := L^{-T} y for the unit lower L that FactorLdltSplit leaves below the diagonal of the
// n x n block (re, im, ld): the back substitution of both block solves.
COMBABC_KERNEL void SolveUnitUpperSplit(const double* re,
                                        const double* im,
                                        std::ptrdiff_t ld,
                                        std::ptrdiff_t n,
                                        double* yr,
                                        double* yi) {
  for (std::ptrdiff_t j = n - 1; j >= 0; --j) {
    double vr = 0.0;
    double vi = 0.0;
    DotSplit(re + j * ld + j + 1, im + j * ld + j + 1, yr + j + 1, yi + j + 1, n - j - 1, &vr, &vi);
    yr[j] -= vr;
    yi[j] -= vi;
  }
}

// SolveUnitUpperSplit for `cases` vectors at once, stored side by side within each entry (as
// DotSplitCases): each gets SolveUnitUpperSplit's bits. `v`: 2 cases doubles of scratch.
COMBABC_KERNEL void SolveUnitUpperSplitCases(const double* re,
                                             const double* im,
                                             std::ptrdiff_t ld,
                                             std::ptrdiff_t n,
                                             double* yr,
                                             double* yi,
                                             std::ptrdiff_t cases,
                                             double* v) {
  double* vr = v;
  double* vi = v + cases;
  for (std::ptrdiff_t j = n - 1; j >= 0; --j) {
    DotSplitCases(re + j * ld + j + 1,
                  im + j * ld + j + 1,
                  yr + (j + 1) * cases,
                  yi + (j + 1) * cases,
                  n - j - 1,
                  cases,
                  vr,
                  vi);
    for (std::ptrdiff_t c = 0; c < cases; ++c) {
      yr[j * cases + c] -= vr[c];
      yi[j * cases + c] -= vi[c];
    }
  }
}

// z = A u - b for the symmetric n x n A given by its lower triangle (ar, ai, leading dimension
// n): the diagonal-block part of both solves' residual checks.
COMBABC_KERNEL void SymmetricResidualSplit(const double* ar,
                                           const double* ai,
                                           std::ptrdiff_t n,
                                           const double* ur,
                                           const double* ui,
                                           const double* br,
                                           const double* bi,
                                           double* zr,
                                           double* zi) {
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    zr[k] = -br[k];
    zi[k] = -bi[k];
  }
  for (std::ptrdiff_t c = 0; c < n; ++c) {
    SubScaledSplit(zr + c, zi + c, ar + c * n + c, ai + c * n + c, -ur[c], -ui[c], n - c);
    double vr = 0.0;
    double vi = 0.0;
    DotSplit(ar + c * n + c + 1, ai + c * n + c + 1, ur + c + 1, ui + c + 1, n - c - 1, &vr, &vi);
    zr[c] += vr;
    zi[c] += vi;
  }
}

// The residual test of both block solves, one block row at a time: max |z| <= kResidualTol
// (max |b| + sqrt(max |A|^2 max |u|^2)) over the rows, with z = A u - b that row's residual.
// Squared moduli keep hypot off the hot path; a NaN anywhere fails the test.
struct ResidualCheck {
  double residual2 = 0.0;
  double scale = 0.0;
  bool finite = true;
  COMBABC_KERNEL void AddRow(const double* zr,
                             const double* zi,
                             const double* br,
                             const double* bi,
                             const double* ur,
                             const double* ui,
                             std::ptrdiff_t n,
                             double a_max2) {
    double z2 = 0.0;
    double z2_sum = 0.0;  // NaN-propagating, unlike std::max
    double b2 = 0.0;
    double u2 = 0.0;
    for (std::ptrdiff_t k = 0; k < n; ++k) {
      const double v = zr[k] * zr[k] + zi[k] * zi[k];
      z2 = std::max(z2, v);
      z2_sum += v;
      b2 = std::max(b2, br[k] * br[k] + bi[k] * bi[k]);
      u2 = std::max(u2, ur[k] * ur[k] + ui[k] * ui[k]);
    }
    residual2 = std::max(residual2, z2);
    finite = finite && std::isfinite(z2_sum);
    scale = std::max(scale, std::sqrt(b2) + std::sqrt(a_max2 * u2));
  }
  bool Passes() const { return finite && std::sqrt(residual2) <= kResidualTol * scale; }
};

// The singularity test of both block solves (plate.hpp, kMaxAmplification), one block row at a
// time: the largest |u| against the largest |b|. A NaN in u fails it.
struct AmplificationCheck {
  double u2 = 0.0;
  double b2 = 0.0;
  COMBABC_KERNEL void AddRow(
      const double* ur, const double* ui, const double* br, const double* bi, std::ptrdiff_t n) {
    double u2_sum = 0.0;  // NaN-propagating, unlike std::max
    for (std::ptrdiff_t k = 0; k < n; ++k) {
      const double v = ur[k] * ur[k] + ui[k] * ui[k];
      u2 = std::max(u2, v);
      u2_sum += v;
      b2 = std::max(b2, br[k] * br[k] + bi[k] * bi[k]);
    }
    if (!std::isfinite(u2_sum)) u2 = std::numeric_limits<double>::infinity();
  }
  bool Passes() const { return u2 <= kMaxAmplification * kMaxAmplification * b2; }
  double amplification() const { return std::sqrt(u2 / b2); }
};

// Largest |a|^2 over the lower triangle of the leading n x n block (split storage). Two running
// maxima per vector lane pair, in the form `m < v ? v : m` that compiles to maxpd (a single
// chained maximum would wait on every compare's latency; NaN entries are skipped, the solves'
// residual checks catch them).
COMBABC_KERNEL double LowerMaxNorm2Split(const double* __restrict re,
                                         const double* __restrict im,
                                         std::ptrdiff_t ld,
                                         std::ptrdiff_t n) {
  double m0 = 0.0;
  double m1 = 0.0;
  double m2 = 0.0;
  double m3 = 0.0;
  for (std::ptrdiff_t j = 0; j < n; ++j) {
    const double* cr = re + j * ld;
    const double* ci = im + j * ld;
    std::ptrdiff_t t = j;
    for (; t + 3 < n; t += 4) {
      const double v0 = cr[t] * cr[t] + ci[t] * ci[t];
      const double v1 = cr[t + 1] * cr[t + 1] + ci[t + 1] * ci[t + 1];
      const double v2 = cr[t + 2] * cr[t + 2] + ci[t + 2] * ci[t + 2];
      const double v3 = cr[t + 3] * cr[t + 3] + ci[t + 3] * ci[t + 3];
      m0 = m0 < v0 ? v0 : m0;
      m1 = m1 < v1 ? v1 : m1;
      m2 = m2 < v2 ? v2 : m2;
      m3 = m3 < v3 ? v3 : m3;
    }
    for (; t < n; ++t) {
      const double v = cr[t] * cr[t] + ci[t] * ci[t];
      m0 = m0 < v ? v : m0;
    }
  }
  return std::max(std::max(m0, m1), std::max(m2, m3));
}

// In place A = L D L^T (unit lower L below the diagonal, D on it), no pivoting and no conjugation,
// of the leading n x n block of the rows x n matrix (re, im, ld) (rows >= n); reads only its lower
// triangle. Rows below it, B (rows - n x n), are carried along and become B L^{-T} D^{-1}: with
// B = [P^T; b^T] that is (D^{-1} L^{-1} P)^T and (D^{-1} L^{-1} b)^T, the triangular solves the
// block elimination needs, done inside the factorization's updates.
// Right-looking: each pivot's column updates the later columns by complex axpys, so the
// inner loops are long, contiguous and free of calls.
// `higham`: the caller knows the matrix is a Higham matrix (section_solve.cpp), whose pivots
// cannot break down; only a zero or non-finite pivot is refused then, without the scan for the
// largest entry that the relative breakdown test needs.
COMBABC_KERNEL bool FactorLdltSplit(double* re,
                                    double* im,
                                    std::ptrdiff_t ld,
                                    std::ptrdiff_t rows,
                                    std::ptrdiff_t n,
                                    bool higham = false) {
  const double scale2 = higham ? 0.0 : LowerMaxNorm2Split(re, im, ld, n);
  // Pivots two at a time: column j + 1 takes pivot j's update first, then both update the later
  // columns in one pass (SubScaled2Split).
  const auto pivot = [&](std::ptrdiff_t j, double* ir, double* ii) COMBABC_KERNEL_LAMBDA {
    const double dr = re[j * ld + j];
    const double di = im[j * ld + j];
    const double d2 = dr * dr + di * di;
    *ir = dr / d2;  // 1 / d
    *ii = -di / d2;
    return d2 > kPivotTol * kPivotTol * scale2;
  };
  // Column j scaled by 1 / d_j below its pivot, once no later column needs it unscaled.
  const auto scale_column = [&](std::ptrdiff_t j, double ir, double ii) COMBABC_KERNEL_LAMBDA {
    double* xr = re + j * ld;
    double* xi = im + j * ld;
    for (std::ptrdiff_t t = j + 1; t < rows; ++t) {
      const double ar = xr[t];
      const double ai = xi[t];
      xr[t] = ar * ir - ai * ii;
      xi[t] = ar * ii + ai * ir;
    }
  };
  std::ptrdiff_t j = 0;
  for (; j + 1 < n; j += 2) {
    double ir0 = 0.0;
    double ii0 = 0.0;
    double ir1 = 0.0;
    double ii1 = 0.0;
    if (!pivot(j, &ir0, &ii0)) return false;
    const double* xr = re + j * ld;
    const double* xi = im + j * ld;
    const double* yr = re + (j + 1) * ld;
    const double* yi = im + (j + 1) * ld;
    // Column j + 1 -= x (x_{j+1} / d_j).
    SubScaledSplit(re + (j + 1) * ld + j + 1,
                   im + (j + 1) * ld + j + 1,
                   xr + j + 1,
                   xi + j + 1,
                   xr[j + 1] * ir0 - xi[j + 1] * ii0,
                   xr[j + 1] * ii0 + xi[j + 1] * ir0,
                   rows - j - 1);
    if (!pivot(j + 1, &ir1, &ii1)) return false;
    // Schur complement of both pivots: column k -= x (x_k / d_j) + y (y_k / d_{j+1}).
    for (std::ptrdiff_t k = j + 2; k < n; ++k) {
      SubScaled2Split(re + k * ld + k,
                      im + k * ld + k,
                      xr + k,
                      xi + k,
                      xr[k] * ir0 - xi[k] * ii0,
                      xr[k] * ii0 + xi[k] * ir0,
                      yr + k,
                      yi + k,
                      yr[k] * ir1 - yi[k] * ii1,
                      yr[k] * ii1 + yi[k] * ir1,
                      rows - k);
    }
    scale_column(j, ir0, ii0);
    scale_column(j + 1, ir1, ii1);
  }
  if (j < n) {
    double ir = 0.0;
    double ii = 0.0;
    if (!pivot(j, &ir, &ii)) return false;
    scale_column(j, ir, ii);
  }
  return true;
}

// The per-thread workspace of a block-tridiagonal solve, reused from call to call: for each block
// row (the free dofs of one unknown cross-section) its assembled diagonal block, its pivot block
// with the rows carried through the factorization, and every load case's right-hand side and
// solution (case j at [j nc, j nc + n)). Each solve extends it with its couplings' storage.
struct BlockWorkspace {
  int nc = -1;
  int rows = -1;     // capacity
  int cases = -1;    // capacity
  int num_rows = 0;  // this call's block rows
  // Pivot blocks F_i ((n + carried) x n, leading dimension n + carried: at most 2 nc + cases),
  // LDL^T in place, with the coupling and the right-hand sides carried below them.
  std::vector<Split> factor;
  std::vector<Split> diagonal;        // assembled diagonal blocks, lower triangles (n x n)
  std::vector<double> diagonal_max2;  // max |a|^2 over each diagonal block
  std::vector<Split> rhs;
  std::vector<Split> u;
  std::vector<const std::vector<int>*> free;  // each row's free dofs (0..nc-1, ascending)
  std::vector<char> fallback;                 // [case]: solved by the pivoting fallback

  // Sizes the storage for rows of nc dofs and `cases` load cases; true when it was (re)allocated,
  // so that the solve sizes its own storage too.
  bool Reserve(int nc_, int rows_, int cases_) {
    if (nc_ == nc && rows_ <= rows && cases_ <= cases) return false;
    nc = nc_;
    rows = std::max(rows_, rows);
    cases = std::max(cases_, cases);
    const Index n = nc;
    const Index k = cases;
    factor.assign(rows, Split{});
    diagonal.assign(rows, Split{});
    rhs.assign(rows, Split{});
    u.assign(rows, Split{});
    for (int i = 0; i < rows; ++i) {
      factor[i].Resize((2 * n + k) * n);
      diagonal[i].Resize(n * n);
      rhs[i].Resize(n * k);
      u[i].Resize(n * k);
    }
    diagonal_max2.assign(rows, 0.0);
    free.assign(rows, nullptr);
    return true;
  }
  // Row i's size, its free dofs; 0 past the last row, so that a chain's phases need no special
  // end.
  COMBABC_KERNEL Index RowSize(int i) const {
    return i < num_rows ? static_cast<Index>(free[i]->size()) : 0;
  }
  bool AnyFallback() const {
    return std::find(fallback.begin(), fallback.end(), 1) != fallback.end();
  }
};

// Flags each case whose solution has too large a residual in the assembled system (ResidualCheck,
// case by case: each has its own scale) for the fallback: the unpivoted path must earn each
// result. `add_couplings(i, at, zr, zi)` adds to row i's residual z the off-diagonal blocks times
// the neighbouring rows' solutions of the case at `at`; the diagonal block's part is common.
template <class AddCouplings>
COMBABC_KERNEL void FlagLargeResiduals(
    BlockWorkspace& ws, Index cases, double* zr, double* zi, const AddCouplings& add_couplings) {
  const Index nc = ws.nc;
  for (Index k = 0; k < cases; ++k) {
    const Index at = k * nc;
    ResidualCheck check;
    for (int i = 0; i < ws.num_rows; ++i) {
      const Index n = ws.RowSize(i);
      if (n == 0) continue;  // a cross-section with every dof fixed has no equation
      const double* ar = ws.diagonal[i].re.data();
      const double* ai = ws.diagonal[i].im.data();
      const double* ur = ws.u[i].re.data() + at;
      const double* ui = ws.u[i].im.data() + at;
      const double* br = ws.rhs[i].re.data() + at;
      const double* bi = ws.rhs[i].im.data() + at;
      // z = A u - rhs, A symmetric from its lower triangle.
      SymmetricResidualSplit(ar, ai, n, ur, ui, br, bi, zr, zi);
      add_couplings(i, at, zr, zi);
      check.AddRow(zr, zi, br, bi, ur, ui, n, ws.diagonal_max2[i]);
    }
    ws.fallback[k] = check.Passes() ? 0 : 1;
  }
}

// The fallback's frame: `big` is the whole assembled system with the rows one after the other
// (RowOffsets) and `lu` a pivoting LU of it (dense or sparse); each case flagged in ws.fallback
// is solved by it and written back into its rows.
inline std::vector<Index> RowOffsets(const BlockWorkspace& ws) {
  std::vector<Index> offset(ws.num_rows + 1, 0);
  for (int i = 0; i < ws.num_rows; ++i) offset[i + 1] = offset[i] + ws.RowSize(i);
  return offset;
}
template <class Lu>
void SolveFlaggedCases(BlockWorkspace& ws,
                       Index cases,
                       const std::vector<Index>& offset,
                       const Lu& lu) {
  const Index nc = ws.nc;
  for (Index j = 0; j < cases; ++j) {
    if (ws.fallback[j] == 0) continue;
    Eigen::VectorXcd b(offset[ws.num_rows]);
    for (int i = 0; i < ws.num_rows; ++i) {
      for (Index k = 0; k < ws.RowSize(i); ++k) {
        b(offset[i] + k) = {ws.rhs[i].re[j * nc + k], ws.rhs[i].im[j * nc + k]};
      }
    }
    const Eigen::VectorXcd solution = lu.solve(b);
    for (int i = 0; i < ws.num_rows; ++i) {
      for (Index k = 0; k < ws.RowSize(i); ++k) {
        ws.u[i].re[j * nc + k] = solution(offset[i] + k).real();
        ws.u[i].im[j * nc + k] = solution(offset[i] + k).imag();
      }
    }
  }
}

// Singular or nearly so (plate.hpp), whichever path solved it: every path, the certified one too,
// since a certificate by Cholesky can pass a matrix that is singular to working precision. Case
// by case: each load's solution against that load.
COMBABC_KERNEL void ThrowIfSingular(const BlockWorkspace& ws, Index cases) {
  const Index nc = ws.nc;
  for (Index j = 0; j < cases; ++j) {
    AmplificationCheck amplification;
    for (int i = 0; i < ws.num_rows; ++i) {
      amplification.AddRow(ws.u[i].re.data() + j * nc,
                           ws.u[i].im.data() + j * nc,
                           ws.rhs[i].re.data() + j * nc,
                           ws.rhs[i].im.data() + j * nc,
                           ws.RowSize(i));
    }
    if (!amplification.Passes()) throw SingularSystem(amplification.amplification());
  }
}

}  // namespace combabc::plate
