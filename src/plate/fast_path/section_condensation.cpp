#include "plate/fast_path/section_condensation.hpp"

#include <cmath>
#include <utility>

#include <Eigen/QR>
#include <Eigen/SparseLU>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/thread_pool.hpp"

namespace combabc::plate {
namespace {

// Group g's outputs: its sections' output positions, section after section, in each set.
OutputLayout GroupOutputs(const SectionLayout& sections, int g, int group_size) {
  OutputLayout layout;
  layout.positions.resize(static_cast<std::size_t>(sections.sets().num_sets()));
  for (int k = 0; k < group_size; ++k) {
    const OutputLayout& section = sections.SectionOutputs(g * group_size + k);
    for (std::size_t set = 0; set < layout.positions.size(); ++set) {
      const std::vector<int>& p = section.positions[set];
      layout.positions[set].insert(layout.positions[set].end(), p.begin(), p.end());
    }
  }
  layout.Finish(sections.sets());
  return layout;
}

}  // namespace

SectionCondensation::SectionCondensation(const Plate& plate,
                                         std::shared_ptr<const SectionLayout> section_layout,
                                         const Settings& settings)
    : layout_(std::move(section_layout)),
      group_size_(settings.group_size),
      always_pivot_(settings.always_pivot),
      higham_(settings.higham),
      kernels_(settings.kernels) {
  const SectionLayout& sections = *layout_;
  const int num_sections = sections.num_sections();
  const int group_size = group_size_;
  const int nc = sections.nc();
  COMBABC_CHECK(plate.grid().nx() == num_sections * sections.intervals());
  COMBABC_CHECK(group_size >= 1 && num_sections % group_size == 0);
  // Sections with the same element sizes, no interior load in any case and outputs at the same
  // relative positions in every output set have identical pieces: compute those once.
  const auto same_section = [&](int s, int t) {
    return !sections.InteriorLoaded(s) && !sections.InteriorLoaded(t) &&
           sections.SameSpacing(s, t) && sections.SameOutputPositions(s, t);
  };
  piece_index_.resize(num_sections);
  std::vector<int> representatives;  // the first section of each distinct kind
  for (int s = 0; s < num_sections; ++s) {
    int twin = -1;
    for (int t = 0; t < s && twin < 0; ++t) {
      if (same_section(s, t)) twin = t;
    }
    for (int state = 0; state < 4; ++state) {
      piece_index_[s][state] = twin >= 0 ? piece_index_[twin][state]
                                         : static_cast<int>(representatives.size()) * 4 + state;
    }
    if (twin < 0) representatives.push_back(s);
  }
  pieces_.resize(representatives.size() * 4);
  section_condensed_.resize(static_cast<std::size_t>(num_sections) * 4);
  for (int state = 0; state < 4; ++state) {
    CondenseSections(plate, state, settings.frequency_hz, representatives);
  }
  // Groups made of the same section pieces with no load on their inner cross-sections are equal.
  const int num_groups = num_sections / group_size;
  const int group_states = 1 << (2 * group_size);
  group_piece_index_.assign(num_groups, std::vector<int>(group_states, -1));
  group_layout_.resize(num_groups);
  const auto same_group = [&](int g, int h) {
    // The first and last groups have the plate's end cross-sections folded in: never shared.
    const auto is_end = [&](int k) { return k == 0 || k == num_groups - 1; };
    if (is_end(g) || is_end(h)) return false;
    for (int k = 0; k < group_size; ++k) {
      if (piece_index_[g * group_size + k] != piece_index_[h * group_size + k]) return false;
      if (k > 0 && (sections.BoundaryLoad(g * group_size + k).cwiseAbs().maxCoeff() != 0.0 ||
                    sections.BoundaryLoad(h * group_size + k).cwiseAbs().maxCoeff() != 0.0)) {
        return false;
      }
    }
    return true;
  };
  // Jacobi scaling folded into the group pieces (CrossSectionScale), from one section piece.
  const Eigen::VectorXd scale = CrossSectionScale(Condensed(pieces_[piece_index_[0][0]]), nc);
  // The distinct groups (not twins) get their pieces, numbered group after group, state after
  // state. Groups whose sections have the same condensed matrices and the same folded ends (all
  // the inner groups of a uniform mesh, loaded or not) share the elimination of their inner
  // cross-sections in each state; only their loads and outputs are their own.
  std::vector<std::vector<int>> classes;  // groups with one elimination
  std::vector<std::vector<int>> class_keys;
  int pieces = 0;
  for (int g = 0; g < num_groups; ++g) {
    group_layout_[g] = GroupOutputs(sections, g, group_size);
    int twin = -1;
    for (int h = 0; h < g && twin < 0; ++h) {
      if (same_group(g, h)) twin = h;
    }
    for (int state = 0; state < group_states; ++state) {
      group_piece_index_[g][state] = twin >= 0 ? group_piece_index_[twin][state] : pieces++;
    }
    if (twin >= 0) continue;
    std::vector<int> key = {g == 0 ? 1 : 0, g == num_groups - 1 ? 1 : 0};
    for (int k = 0; k < group_size; ++k) key.push_back(sections.MeshOfSection(g * group_size + k));
    std::size_t c = 0;
    while (c < classes.size() && class_keys[c] != key) ++c;
    if (c == classes.size()) {
      classes.emplace_back();
      class_keys.push_back(key);
    }
    classes[c].push_back(g);
  }
  // Each (class, state) depends on nothing else: computed on the pool's threads, every piece is
  // the same for any thread count, and no more than one elimination per thread is alive.
  group_pieces_.resize(static_cast<std::size_t>(pieces));
  const auto compose = [&](std::size_t begin, std::size_t end) {
    for (std::size_t item = begin; item < end; ++item) {
      const std::vector<int>& groups = classes[item / group_states];
      const int state = static_cast<int>(item % group_states);
      const GroupElimination elimination = EliminateGroup(groups.front(), state, scale);
      for (int g : groups) {
        group_pieces_[group_piece_index_[g][state]] = FinishGroup(elimination, g, state, scale);
      }
    }
  };
  const std::size_t items = classes.size() * static_cast<std::size_t>(group_states);
  if (settings.pool != nullptr) {
    settings.pool->ParallelFor(items, 1, compose);
  } else {
    compose(0, items);
  }
  // The composition read the unscaled cross-section loads; Solve reads them scaled.
  for (int c = 0; c <= num_sections; ++c) {
    boundary_load_.push_back(scale.asDiagonal() * sections.BoundaryLoad(c));
  }
  // Only the group pieces are read per configuration. (Released last: released before the group
  // pieces are allocated, their memory would hold them, scattered, and the per-configuration
  // solve, which reads pieces all over the 20 MB, measured 15 % slower.)
  std::vector<Piece>().swap(pieces_);
  std::vector<Eigen::MatrixXcd>().swap(section_condensed_);
  std::vector<std::array<int, 4>>().swap(piece_index_);
}

SectionCondensation::GroupElimination SectionCondensation::EliminateGroup(
    int group, int state, const Eigen::VectorXd& scale) const {
  const int g = group_size_;
  const int nc = layout_->nc();
  const int first = group * g;
  const auto section_state = [&](int k) { return (state >> (2 * k)) & 3; };
  GroupElimination e;
  // Group dofs z: cross-section t = 0..g of the group at [t nc, (t + 1) nc). The two ends are
  // kept (index into [left; right]) unless they are the plate's ends, which are folded in; inner
  // cross-sections keep their free dofs (interior).
  const bool fold_left = first == 0;
  const bool fold_right = first + g == layout_->num_sections();
  e.left_size = fold_left ? 0 : nc;
  e.right_size = fold_right ? 0 : nc;
  const int nz = (g + 1) * nc;
  e.boundary_index.assign(nz, -1);
  e.interior_index.assign(nz, -1);
  for (int d = 0; d < nc; ++d) {
    if (!fold_left) e.boundary_index[d] = d;
    if (!fold_right) e.boundary_index[g * nc + d] = e.left_size + d;
  }
  int n_interior = 0;
  for (int t = 0; t <= g; ++t) {
    if ((t == 0 && !fold_left) || (t == g && !fold_right)) continue;
    e.interior_cross_sections.push_back(t);
    const int left = t > 0 ? section_state(t - 1) : 0;
    const int right = t < g ? section_state(t) : 0;
    const std::vector<int>& free =
        layout_->FreeDofs(first + t, ((left | right) & 1) != 0, ((left | right) & 2) != 0);
    for (int d : free) e.interior_index[t * nc + d] = n_interior++;
  }
  const int nb = e.left_size + e.right_size;
  const int np = 2 * nc;  // a section piece's size
  Eigen::MatrixXcd k_bb = Eigen::MatrixXcd::Zero(nb, nb);
  e.k_bi = Eigen::MatrixXcd::Zero(nb, n_interior);
  Eigen::MatrixXcd k_ib = Eigen::MatrixXcd::Zero(n_interior, nb);
  Eigen::MatrixXcd k_ii = Eigen::MatrixXcd::Zero(n_interior, n_interior);
  for (int k = 0; k < g; ++k) {
    const Eigen::MatrixXcd& condensed =
        Condensed(pieces_[piece_index_[first + k][section_state(k)]]);
    for (int c = 0; c < np; ++c) {
      const int zc = k * nc + c;  // the piece's [left; right] are cross-sections k and k + 1
      const int cb = e.boundary_index[zc];
      const int ci = e.interior_index[zc];
      for (int r = 0; r < np; ++r) {
        const int zr = k * nc + r;
        const int rb = e.boundary_index[zr];
        const int ri = e.interior_index[zr];
        const std::complex<double> v = condensed(r, c);
        if (rb >= 0 && cb >= 0) {
          k_bb(rb, cb) += v;
        } else if (rb >= 0 && ci >= 0) {
          e.k_bi(rb, ci) += v;
        } else if (ri >= 0 && cb >= 0) {
          k_ib(ri, cb) += v;
        } else if (ri >= 0 && ci >= 0) {
          k_ii(ri, ci) += v;
        }
      }
    }
  }
  e.x_b = Eigen::MatrixXcd::Zero(n_interior, nb);
  if (n_interior > 0) {
    // Jacobi-scaled (see Plate::SolveHarmonic).
    e.scale = k_ii.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
    e.lu.compute(e.scale.asDiagonal() * k_ii * e.scale.asDiagonal());
    // Empty products are skipped: Eigen binds references to their (null) data in Debug.
    if (nb > 0) e.x_b = e.scale.asDiagonal() * e.lu.solve(e.scale.asDiagonal() * k_ib);
  }
  // What Solve reads of the matrix, with the cross-section scale folded in.
  Eigen::VectorXd s(nb);
  if (e.left_size > 0) s.head(nc) = scale;
  if (e.right_size > 0) s.tail(nc) = scale;
  const Eigen::MatrixXcd condensed = s.asDiagonal() * (k_bb - e.k_bi * e.x_b) * s.asDiagonal();
  SolvePiece& out = e.blocks;
  out.left_size = e.left_size;
  out.right_size = e.right_size;
  if (e.left_size > 0) out.left_block = SplitMatrix(condensed.topLeftCorner(nc, nc));
  if (e.right_size > 0) out.right_block = SplitMatrix(condensed.bottomRightCorner(nc, nc));
  if (e.left_size > 0 && e.right_size > 0) {
    // The coupling between a group's two end cross-sections passes through 15 cm of strip, where
    // all but a few cross-section shapes have decayed: its singular values fall from O(1) to
    // about 1e-19 times the piece's largest entry. A column-pivoted QR reveals that rank at a
    // fraction of an SVD's cost: |R_kk| decreases and tracks the singular values to within a
    // modest factor. Keeping the columns with |R_kk| above kRankTol times that entry (far below
    // the round-off of the condensation itself) makes the coupling a product of two nc x rank
    // factors (rank 5-8 at the default mesh), which the per-configuration solve exploits.
    constexpr double kRankTol = 1e-17;
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXcd> qr(condensed.topRightCorner(nc, nc));
    const double cutoff = kRankTol * condensed.cwiseAbs().maxCoeff();
    const Eigen::MatrixXcd& packed = qr.matrixQR();
    Eigen::Index rank = 0;
    while (rank < nc && std::abs(packed(rank, rank)) > cutoff) ++rank;
    // coupling P = Q R, so coupling = Q_r (R_r P^T) = Q_r (P R_r^T)^T over the kept rows of R.
    const Eigen::MatrixXcd q = qr.householderQ() * Eigen::MatrixXcd::Identity(nc, rank);
    const Eigen::MatrixXcd r = packed.topRows(rank).triangularView<Eigen::Upper>().toDenseMatrix();
    out.coupling_left = SplitMatrix(q);
    out.coupling_right = SplitMatrix(qr.colsPermutation() * r.transpose());
  }
  return e;
}

SectionCondensation::SolvePiece SectionCondensation::FinishGroup(
    const GroupElimination& e, int group, int state, const Eigen::VectorXd& scale) const {
  const int g = group_size_;
  const int nc = layout_->nc();
  const int first = group * g;
  const auto section_state = [&](int k) { return (state >> (2 * k)) & 3; };
  const int nb = e.left_size + e.right_size;
  const auto n_interior = static_cast<int>(e.x_b.rows());
  const int np = 2 * nc;
  const int cases = layout_->num_cases();
  Eigen::MatrixXcd g_b = Eigen::MatrixXcd::Zero(nb, cases);
  Eigen::MatrixXcd g_i = Eigen::MatrixXcd::Zero(n_interior, cases);
  for (int k = 0; k < g; ++k) {
    const Piece& piece = pieces_[piece_index_[first + k][section_state(k)]];
    for (int c = 0; c < np; ++c) {
      const int zc = k * nc + c;
      if (e.boundary_index[zc] >= 0) g_b.row(e.boundary_index[zc]) += piece.load.row(c);
      if (e.interior_index[zc] >= 0) g_i.row(e.interior_index[zc]) += piece.load.row(c);
    }
  }
  for (int t : e.interior_cross_sections) {
    for (int d = 0; d < nc; ++d) {
      if (e.interior_index[t * nc + d] >= 0) {
        g_i.row(e.interior_index[t * nc + d]) += layout_->BoundaryLoad(first + t).row(d);
      }
    }
  }
  Eigen::MatrixXcd x_f = Eigen::MatrixXcd::Zero(n_interior, cases);
  double singular = 0.0;
  // One load column at a time, each as the vector it was with a single case.
  for (int c = 0; c < cases && n_interior > 0; ++c) {
    const Eigen::VectorXcd scaled_load = e.scale.asDiagonal() * g_i.col(c);
    const Eigen::VectorXcd y = e.lu.solve(scaled_load);
    x_f.col(c) = e.scale.asDiagonal() * y;
    // With a kept end the interior is held by it; without one (the whole plate in one group)
    // this is the configuration's whole solve, and may be singular (plate.hpp).
    const double load = scaled_load.cwiseAbs().maxCoeff();
    if (nb == 0 && load > 0.0) {
      const double amplification = y.cwiseAbs().maxCoeff() / load;
      if (!(amplification <= kMaxAmplification) && !(amplification <= singular)) {
        singular = amplification;
      }
    }
  }
  Eigen::MatrixXcd load(nb, cases);
  for (int c = 0; c < cases && nb > 0; ++c) {
    const Eigen::VectorXcd x = x_f.col(c);
    load.col(c) = g_b.col(c) - e.k_bi * x;
  }
  // The outputs: map rows set after set, each set's rows section after section; offsets case
  // after case in the rows of the case's set (OutputLayout).
  const OutputSets& sets = layout_->sets();
  const OutputLayout& layout = group_layout_[group];
  Eigen::MatrixXcd output_map = Eigen::MatrixXcd::Zero(layout.map_rows(), nb);
  SolvePiece out = e.blocks;
  out.singular = singular;
  out.output_offset = Eigen::VectorXcd::Zero(layout.offset_rows());
  for (int set = 0; set < sets.num_sets(); ++set) {
    const std::vector<int>& set_cases = sets.cases_of_set[set];
    int row = layout.map_begin[set];
    for (int k = 0; k < g; ++k) {
      const Piece& piece = pieces_[piece_index_[first + k][section_state(k)]];
      const OutputLayout& section = layout_->SectionOutputs(first + k);
      const auto rows = static_cast<int>(section.positions[set].size());
      for (int o = 0; o < rows; ++o, ++row) {
        const int t = row - layout.map_begin[set];  // the row within the set
        for (int c : set_cases) {
          out.output_offset(layout.offset_begin[c] + t) =
              piece.output_offset(section.offset_begin[c] + o);
        }
        for (int c = 0; c < np; ++c) {
          const int zc = k * nc + c;
          const std::complex<double> v = piece.output_map(section.map_begin[set] + o, c);
          if (e.boundary_index[zc] >= 0) {
            output_map(row, e.boundary_index[zc]) += v;
          } else if (e.interior_index[zc] >= 0) {
            // No kept end, no columns: a row of an empty matrix is null data plus an offset (UB).
            if (nb > 0) output_map.row(row) -= v * e.x_b.row(e.interior_index[zc]);
            for (int lc : set_cases) {
              out.output_offset(layout.offset_begin[lc] + t) += v * x_f(e.interior_index[zc], lc);
            }
          }
        }
      }
    }
  }
  Eigen::VectorXd s(nb);
  if (e.left_size > 0) s.head(nc) = scale;
  if (e.right_size > 0) s.tail(nc) = scale;
  out.load = s.asDiagonal() * load;
  out.output_map = SplitMatrix(output_map * s.asDiagonal());
  return out;
}

void SectionCondensation::CondenseSections(const Plate& plate,
                                           int state,
                                           double frequency_hz,
                                           const std::vector<int>& representatives) {
  const Eigen::MatrixXd& loads = layout_->loads();
  const std::vector<CaseOutputs>& outputs = layout_->outputs();
  const OutputSets& sets = layout_->sets();
  const int nc = layout_->nc();
  const int num_cases = layout_->num_cases();
  const int m = layout_->intervals();
  const int n_local = (m + 1) * nc;
  // Classify local dofs: boundary (index into [left; right]), interior (index into I), or fixed.
  // The same for every section in this state.
  std::vector<int> boundary_index;
  std::vector<int> interior_index;
  const int n_interior = layout_->ClassifySectionDofs(state, &boundary_index, &interior_index);
  const int nb = 2 * nc;
  const std::complex<double> mass_coefficient = plate.MassCoefficient(frequency_hz);
  const std::complex<double> i_unit(0.0, 1.0);
  for (std::size_t first = 0; first < representatives.size(); ++first) {
    const int mesh = layout_->MeshOfSection(representatives[first]);
    bool seen = false;  // each mesh once, at its first distinct section
    for (std::size_t q = 0; q < first; ++q) {
      seen = seen || layout_->MeshOfSection(representatives[q]) == mesh;
    }
    if (seen) continue;
    // The section matrices of the mesh (its first section: the others have the same elements).
    Eigen::MatrixXcd s_bb = Eigen::MatrixXcd::Zero(nb, nb);
    Eigen::MatrixXcd s_ib = Eigen::MatrixXcd::Zero(n_interior, nb);
    std::vector<Eigen::Triplet<std::complex<double>>> triplets;
    ForEachSectionEntry(
        plate, mesh, m, [&](const ElementMatrices& e, int r, int c, int lr, int lc) {
          const std::complex<double> v = e.stiffness_real(r, c) + i_unit * e.stiffness_imag(r, c) +
                                         mass_coefficient * e.mass_unit(r, c);
          const int rb = boundary_index[lr];
          const int cb = boundary_index[lc];
          const int ri = interior_index[lr];
          const int ci = interior_index[lc];
          if (rb >= 0 && cb >= 0) s_bb(rb, cb) += v;
          if (ri >= 0 && cb >= 0) s_ib(ri, cb) += v;
          if (ri >= 0 && ci >= 0) triplets.emplace_back(ri, ci, v);
        });
    Eigen::MatrixXcd x_b = Eigen::MatrixXcd::Zero(n_interior, nb);
    // Complex symmetric: LU, never a Cholesky-type factorization (they conjugate).
    Eigen::SparseLU<Eigen::SparseMatrix<std::complex<double>>, Eigen::COLAMDOrdering<int>> lu;
    Eigen::VectorXd scale;
    if (n_interior > 0) {
      Eigen::SparseMatrix<std::complex<double>> s_ii(n_interior, n_interior);
      s_ii.setFromTriplets(triplets.begin(), triplets.end());
      s_ii.makeCompressed();
      // Jacobi-scaled (see Plate::SolveHarmonic).
      scale = s_ii.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
      s_ii = scale.asDiagonal() * s_ii * scale.asDiagonal();
      s_ii.makeCompressed();
      lu.compute(s_ii);
      if (lu.info() != Eigen::Success) {
        throw Error(ErrorKind::kSoftware, "section condensation: singular interior matrix");
      }
      x_b = scale.asDiagonal() * lu.solve(scale.asDiagonal() * s_ib);
    }
    // S_BI = S_IB^T (complex symmetric: transpose, not adjoint). Only the interior dofs of the
    // elements next to the two end cross-sections couple to them: the products run over those
    // rows of S_IB alone (a few node lines of the section's interior).
    std::vector<int> coupled;
    for (int i = 0; i < n_interior; ++i) {
      if (s_ib.row(i).cwiseAbs().maxCoeff() != 0.0) coupled.push_back(i);
    }
    const Eigen::MatrixXcd s_cb = s_ib(coupled, Eigen::all);
    const int condensed = mesh * 4 + state;
    section_condensed_[condensed] = s_bb - s_cb.transpose() * x_b(coupled, Eigen::all);
    // Each distinct section of this mesh: its loads and its outputs.
    for (std::size_t q = first; q < representatives.size(); ++q) {
      const int section = representatives[q];
      if (layout_->MeshOfSection(section) != mesh) continue;
      const int offset = section * m * nc;
      Piece& piece = pieces_[q * 4 + static_cast<std::size_t>(state)];
      piece.condensed = condensed;
      piece.load.resize(nb, num_cases);
      Eigen::MatrixXcd x_f = Eigen::MatrixXcd::Zero(n_interior, num_cases);
      for (int c = 0; c < num_cases; ++c) {
        Eigen::VectorXcd f_interior = Eigen::VectorXcd::Zero(n_interior);
        for (int d = 0; d < n_local; ++d) {
          if (interior_index[d] >= 0) f_interior(interior_index[d]) = loads(offset + d, c);
        }
        Eigen::VectorXcd x = Eigen::VectorXcd::Zero(n_interior);
        if (n_interior > 0) x = scale.asDiagonal() * lu.solve(scale.asDiagonal() * f_interior);
        piece.load.col(c) = -s_cb.transpose() * x(coupled);
        x_f.col(c) = x;
      }
      const OutputLayout& layout = layout_->SectionOutputs(section);
      piece.output_map = Eigen::MatrixXcd::Zero(layout.map_rows(), nb);
      piece.output_offset = Eigen::VectorXcd::Zero(layout.offset_rows());
      for (int set = 0; set < sets.num_sets(); ++set) {
        const CaseOutputs& o = outputs[static_cast<std::size_t>(sets.case_of_set[set])];
        const std::vector<int>& positions = layout.positions[set];
        for (std::size_t t = 0; t < positions.size(); ++t) {
          const int row_index = layout.map_begin[set] + static_cast<int>(t);
          int dofs[kMaxElementDofs];
          ElementVector row;
          plate.InterpolationRow(o.x[positions[t]], o.y, dofs, &row);
          for (int q2 = 0; q2 < plate.element_dofs(); ++q2) {
            const int d = dofs[q2] - offset;
            COMBABC_CHECK(d >= 0 && d < n_local);
            if (boundary_index[d] >= 0) {
              piece.output_map(row_index, boundary_index[d]) += row(q2);
            } else if (interior_index[d] >= 0) {
              piece.output_map.row(row_index) -= row(q2) * x_b.row(interior_index[d]);
              for (int c : sets.cases_of_set[set]) {
                piece.output_offset(layout.offset_begin[c] + static_cast<int>(t)) +=
                    row(q2) * x_f(interior_index[d], c);
              }
            }
          }
        }
      }
    }
  }
}

const SectionCondensation::SolvePiece& SectionCondensation::GroupPieceOf(
    int group, std::span<const std::uint8_t> clamps) const {
  const ClampPattern pattern(clamps, layout_->num_sections());
  int state = 0;
  for (int k = 0; k < group_size_; ++k) {
    state |= pattern.State(group * group_size_ + k) << (2 * k);
  }
  return group_pieces_[group_piece_index_[group][state]];
}

std::size_t SectionCondensation::MemoryBytes() const {
  std::size_t bytes = 0;
  for (const SolvePiece& p : group_pieces_) {
    bytes += p.left_block.Bytes() + p.right_block.Bytes() + p.coupling_left.Bytes() +
             p.coupling_right.Bytes() + p.output_map.Bytes() +
             sizeof(std::complex<double>) *
                 static_cast<std::size_t>(p.load.size() + p.output_offset.size());
  }
  for (const auto& b : boundary_load_) {
    bytes += sizeof(std::complex<double>) * static_cast<std::size_t>(b.size());
  }
  return bytes;
}

}  // namespace combabc::plate
