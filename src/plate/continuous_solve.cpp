// The per-call solve with continuous unknowns (docs/model.md, "Continuous unknowns"): evaluate the
// section pieces of the clamp states this configuration uses at its mu (series or direct, see
// continuous_condensation.hpp), then solve the block-tridiagonal system on the num_sections + 1
// cross-sections. Unlike the clamp-only fast path there are no group pieces (64 states per group
// at every mu would cost more than the chain they save) and the couplings are full blocks (a
// section's end-to-end coupling has full numerical rank: 5 cm of strip damp its cross-section
// shapes only to 1e-16). The block elimination is the same unpivoted complex-symmetric LDL^T with
// a residual check (block_ldlt.hpp); the fallback is a sparse LU of the assembled system.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/SparseLU>

#include "block_ldlt.hpp"
#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "continuous_condensation.hpp"

namespace combabc::plate {

// One call's section pieces: per (mesh, state) the packed piece (PackPiece); per (distinct
// section, state) the output map (n_out x 2 nc by columns), then, when loaded, the load (2 nc) and
// the output offset (n_out).
struct ContinuousCondensation::Evaluated {
  std::vector<char> state_needed;
  std::vector<char> kind_needed;
  std::vector<Eigen::VectorXcd> piece;
  std::vector<Eigen::VectorXcd> section;
  Eigen::MatrixXd acc;  // real and imaginary parts of a table's sum
};

namespace {

using Complex = std::complex<double>;

struct Workspace {
  // Pivot blocks F_c, LDL^T in place, with U_c^T and the right-hand side carried below them.
  std::vector<Eigen::MatrixXcd> factor;
  std::vector<Eigen::MatrixXcd> diagonal;  // assembled diagonal blocks (lower triangles)
  std::vector<Eigen::MatrixXcd> coupling;  // U_c between rows c and c + 1
  std::vector<Eigen::VectorXcd> rhs;
  std::vector<Eigen::VectorXcd> u;
  std::vector<std::vector<int>> free;
  std::vector<int> state;
  Eigen::MatrixXcd dv;
  Eigen::VectorXcd tmp;
  Eigen::VectorXcd ends;
  Eigen::VectorXcd values;

  void Reserve(int nc, int rows) {
    if (static_cast<int>(factor.size()) >= rows && dv.rows() == nc) return;
    factor.assign(rows, Eigen::MatrixXcd(2 * nc + 1, nc));
    diagonal.assign(rows, Eigen::MatrixXcd(nc, nc));
    coupling.assign(rows, Eigen::MatrixXcd(nc, nc));
    rhs.assign(rows, Eigen::VectorXcd(nc));
    u.assign(rows, Eigen::VectorXcd(nc));
    free.assign(rows, {});
    dv.resize(nc, nc);
    tmp.resize(nc);
    ends.resize(2 * static_cast<Eigen::Index>(nc));
  }
};

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
    const Eigen::Index map_size = sec.r_b.size();
    Eigen::VectorXcd& out = e->section[k];
    out.resize(map_size + (sec.loaded ? 2 * nc_ + sec.num_outputs : 0));
    out.head(map_size) =
        (sec.r_b - sec.r_i(Eigen::all, sec.read) * x(sec.read, Eigen::all)).reshaped();
    if (sec.loaded) {
      const Eigen::VectorXcd y = solve(sec.f_i);
      out.segment(map_size, 2 * nc_) = -s_ib(coupled, Eigen::all).transpose() * y(coupled);
      out.tail(sec.num_outputs) = sec.r_i(Eigen::all, sec.read) * y(sec.read);
    }
  }
}

void ContinuousCondensation::Solve(std::span<const std::uint8_t> clamps,
                                   Complex mu,
                                   std::span<std::complex<double>> w) const {
  const int ns = num_sections_;
  const int nc = nc_;
  const int rows = ns + 1;  // every cross-section c = 0..ns is a row
  thread_local Workspace ws;
  thread_local Evaluated e;
  ws.Reserve(nc, rows);
  ws.state.resize(ns);
  const std::size_t num_states = states_.size();
  const std::size_t num_kind_states = sections_.size();
  e.state_needed.assign(num_states, 0);
  e.kind_needed.assign(num_kind_states, 0);
  if (e.piece.size() < num_states) e.piece.resize(num_states);
  if (e.section.size() < num_kind_states) e.section.resize(num_kind_states);
  for (int s = 0; s < ns; ++s) {
    const int state = (clamps[s] != 0 ? 1 : 0) | (clamps[ns + s] != 0 ? 2 : 0);
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
  // Free dofs of each cross-section: a node on edge A (B) is fixed when either adjoining section
  // fixes it; the short edges fix the first and last.
  for (int c = 0; c < rows; ++c) {
    const bool a = (c > 0 && clamps[c - 1] != 0) || (c < ns && clamps[c] != 0);
    const bool b = (c > 0 && clamps[ns + c - 1] != 0) || (c < ns && clamps[ns + c] != 0);
    FreeDofs(c, a, b, &ws.free[c]);
  }
  const auto piece_of = [&](int s) -> const Complex* {
    return e.piece[static_cast<std::size_t>(mesh_kind_[s]) * 4 + ws.state[s]].data();
  };
  const auto section_of = [&](int s) -> const Eigen::VectorXcd& {
    return e.section[static_cast<std::size_t>(kind_[s]) * 4 + ws.state[s]];
  };
  const auto loaded = [&](int s) {
    return sections_[static_cast<std::size_t>(kind_[s]) * 4 + ws.state[s]].loaded;
  };
  const auto load_of = [&](int s) {
    const auto map_size = static_cast<Eigen::Index>(section_outputs_[s].size()) * 2 * nc;
    return section_of(s).segment(map_size, 2 * nc);
  };
  const Eigen::Index right_block = LowerStart(nc);  // = nc (nc + 1) / 2
  const Eigen::Index coupling_block = 2 * right_block;
  // Assemble: row c gets the right block of section c - 1 and the left block of section c (lower
  // triangles); section c couples rows c and c + 1.
  for (int c = 0; c < rows; ++c) {
    const std::vector<int>& f = ws.free[c];
    const auto n = static_cast<Eigen::Index>(f.size());
    auto a = ws.diagonal[c].topLeftCorner(n, n);
    auto r = ws.rhs[c].head(n);
    r = boundary_load_[c](f);
    const Complex* left = c > 0 ? piece_of(c - 1) + right_block : nullptr;
    const Complex* right = c < ns ? piece_of(c) : nullptr;
    const Complex* only = left != nullptr ? left : right;  // the plate's end cross-sections
    COMBABC_CHECK(only != nullptr);  // a cross-section has a section on at least one side
    for (Eigen::Index j = 0; j < n; ++j) {
      const Eigen::Index start = LowerStart(f[j]) - f[j];
      if (left != nullptr && right != nullptr) {
        for (Eigen::Index i = j; i < n; ++i) a(i, j) = left[start + f[i]] + right[start + f[i]];
      } else {
        for (Eigen::Index i = j; i < n; ++i) a(i, j) = only[start + f[i]];
      }
    }
    if (c > 0 && loaded(c - 1)) r += load_of(c - 1).tail(nc)(f);
    if (c < ns) {
      if (loaded(c)) r += load_of(c).head(nc)(f);
      const std::vector<int>& g = ws.free[c + 1];
      const Eigen::Map<const Eigen::MatrixXcd> coupling(right + coupling_block, nc, nc);
      ws.coupling[c].topLeftCorner(n, static_cast<Eigen::Index>(g.size())) = coupling(f, g);
    }
  }
  // Block LDL^T elimination: F_0 = A_0, F_{c+1} = A_{c+1} - U_c^T F_c^{-1} U_c. FactorLdlt turns
  // the carried rows U_c^T and r'_c^T into V_c^T = (D^{-1} L^{-1} U_c)^T and w_c^T, so that
  // U_c^T F_c^{-1} U_c = V_c^T D V_c and r'_{c+1} = r_{c+1} - V_c^T D w_c.
  const auto size = [&](int c) { return static_cast<Eigen::Index>(ws.free[c].size()); };
  const auto next_size = [&](int c) { return c + 1 < rows ? size(c + 1) : Eigen::Index{0}; };
  bool ok = !always_pivot_;
  for (int c = 0; c < rows && ok; ++c) {
    const Eigen::Index n = size(c);
    const Eigen::Index m = next_size(c);
    auto ext = ws.factor[c].topLeftCorner(n + m + 1, n);
    if (c == 0) {
      ext.topRows(n).triangularView<Eigen::Lower>() = ws.diagonal[0].topLeftCorner(n, n);
      ext.row(n + m) = ws.rhs[0].head(n).transpose();
    }
    if (m > 0) ext.middleRows(n, m) = ws.coupling[c].topLeftCorner(n, m).transpose();
    ok = FactorLdlt(ext, ws.tmp.head(n));
    if (!ok || m == 0) break;
    const Eigen::Index m2 = next_size(c + 1);
    const auto vt = ext.middleRows(n, m);  // V_c^T
    auto dv = ws.dv.topLeftCorner(n, m);   // D_c V_c
    dv.noalias() = ext.diagonal().asDiagonal() * vt.transpose();
    auto next = ws.factor[c + 1].topLeftCorner(m + m2 + 1, m);
    next.topRows(m).triangularView<Eigen::Lower>() = ws.diagonal[c + 1].topLeftCorner(m, m);
    next.topRows(m).triangularView<Eigen::Lower>() -= vt * dv;
    auto b = ws.tmp.head(m);
    b = ws.rhs[c + 1].head(m);
    b.noalias() -= dv.transpose() * ext.row(n + m).transpose();
    next.row(m + m2) = b.transpose();
  }
  // Back substitution: u_c = L_c^{-T} (w_c - V_c u_{c+1}).
  for (int c = rows - 1; c >= 0 && ok; --c) {
    const Eigen::Index n = size(c);
    const Eigen::Index m = next_size(c);
    const auto ext = ws.factor[c].topLeftCorner(n + m + 1, n);
    auto y = ws.tmp.head(n);
    y = ext.row(n + m).transpose();
    if (m > 0) y.noalias() -= ext.middleRows(n, m).transpose() * ws.u[c + 1].head(m);
    ext.topRows(n).transpose().triangularView<Eigen::UnitUpper>().solveInPlace(y);
    ws.u[c].head(n) = y;
  }
  // Residual of the assembled system; the unpivoted path must earn its result.
  if (ok) {
    double residual = 0.0;
    double scale = 0.0;
    for (int c = 0; c < rows; ++c) {
      const Eigen::Index n = size(c);
      if (n == 0) continue;  // a cross-section with every dof fixed has no equation
      auto r = ws.tmp.head(n);
      const auto a = ws.diagonal[c].topLeftCorner(n, n);
      r.noalias() = a.triangularView<Eigen::Lower>() * ws.u[c].head(n);
      r.noalias() += a.triangularView<Eigen::StrictlyLower>().transpose() * ws.u[c].head(n);
      r -= ws.rhs[c].head(n);
      if (c + 1 < rows) {
        r.noalias() += ws.coupling[c].topLeftCorner(n, size(c + 1)) * ws.u[c + 1].head(size(c + 1));
      }
      if (c > 0) {
        r.noalias() += ws.coupling[c - 1].topLeftCorner(size(c - 1), n).transpose() *
                       ws.u[c - 1].head(size(c - 1));
      }
      residual = std::max(residual, r.cwiseAbs2().maxCoeff());
      double a2 = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        a2 = std::max(a2, a.col(j).tail(n - j).cwiseAbs2().maxCoeff());
      }
      scale = std::max(scale,
                       std::sqrt(ws.rhs[c].head(n).cwiseAbs2().maxCoeff()) +
                           std::sqrt(a2 * ws.u[c].head(n).cwiseAbs2().maxCoeff()));
    }
    ok = std::sqrt(residual) <= kResidualTol * scale;
  }
  if (!ok) {
    // Fallback: sparse partial-pivoting LU of the assembled block-tridiagonal system.
    std::vector<Eigen::Index> offset(rows + 1, 0);
    for (int c = 0; c < rows; ++c) offset[c + 1] = offset[c] + size(c);
    std::vector<Eigen::Triplet<Complex>> triplets;
    Eigen::VectorXcd big_rhs(offset[rows]);
    for (int c = 0; c < rows; ++c) {
      const Eigen::Index n = size(c);
      const auto a = ws.diagonal[c].topLeftCorner(n, n);
      for (Eigen::Index j = 0; j < n; ++j) {
        for (Eigen::Index i = j; i < n; ++i) {
          triplets.emplace_back(offset[c] + i, offset[c] + j, a(i, j));
          if (i != j) triplets.emplace_back(offset[c] + j, offset[c] + i, a(i, j));
        }
      }
      big_rhs.segment(offset[c], n) = ws.rhs[c].head(n);
      if (c + 1 < rows) {
        const Eigen::Index m = size(c + 1);
        for (Eigen::Index j = 0; j < m; ++j) {
          for (Eigen::Index i = 0; i < n; ++i) {
            const Complex v = ws.coupling[c](i, j);
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
    const Eigen::VectorXcd solution = lu.solve(big_rhs);
    for (int c = 0; c < rows; ++c) ws.u[c].head(size(c)) = solution.segment(offset[c], size(c));
  }
  // Outputs of section s from its two end cross-sections.
  for (int s = 0; s < ns; ++s) {
    const std::vector<int>& outputs = section_outputs_[s];
    if (outputs.empty()) continue;
    const auto n_out = static_cast<Eigen::Index>(outputs.size());
    const Eigen::VectorXcd& section = section_of(s);
    auto ends = ws.ends.head(2 * nc);
    ends.setZero();
    ends.head(nc)(ws.free[s]) = ws.u[s].head(size(s));
    ends.tail(nc)(ws.free[s + 1]) = ws.u[s + 1].head(size(s + 1));
    if (ws.values.size() < n_out) ws.values.resize(n_out);
    auto values = ws.values.head(n_out);
    if (loaded(s)) {
      values = section.tail(n_out);
    } else {
      values.setZero();
    }
    values.noalias() += Eigen::Map<const Eigen::MatrixXcd>(
                            section.data(), n_out, 2 * static_cast<Eigen::Index>(nc)) *
                        ends;
    for (std::size_t o = 0; o < outputs.size(); ++o) {
      w[outputs[o]] = values(static_cast<Eigen::Index>(o));
    }
  }
}

}  // namespace combabc::plate
