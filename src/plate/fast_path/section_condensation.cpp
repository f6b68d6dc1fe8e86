#include "plate/fast_path/section_condensation.hpp"

#include <cmath>
#include <utility>

#include <Eigen/SVD>
#include <Eigen/SparseLU>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc::plate {

OutputSets::OutputSets(const std::vector<CaseOutputs>& outputs) {
  first_output.push_back(0);
  for (std::size_t c = 0; c < outputs.size(); ++c) {
    int set = -1;
    for (int k = 0; k < num_sets() && set < 0; ++k) {
      const CaseOutputs& other = outputs[static_cast<std::size_t>(case_of_set[k])];
      if (other.y == outputs[c].y && other.x == outputs[c].x) set = k;
    }
    if (set < 0) {
      set = num_sets();
      case_of_set.push_back(static_cast<int>(c));
      cases_of_set.emplace_back();
    }
    set_of_case.push_back(set);
    cases_of_set[static_cast<std::size_t>(set)].push_back(static_cast<int>(c));
    first_output.push_back(first_output.back() + outputs[c].x.size());
  }
}

void OutputLayout::Finish(const OutputSets& sets) {
  map_begin.assign(1, 0);
  for (const std::vector<int>& p : positions) {
    map_begin.push_back(map_begin.back() + static_cast<int>(p.size()));
  }
  offset_begin.assign(1, 0);
  for (int c = 0; c < sets.num_cases(); ++c) {
    offset_begin.push_back(offset_begin.back() + rows_of_case(sets, c));
  }
}

void AssignOutputs(const Plate& plate,
                   int num_sections,
                   int intervals,
                   const std::vector<CaseOutputs>& outputs,
                   const OutputSets& sets,
                   std::vector<OutputLayout>* layouts,
                   std::vector<std::vector<std::vector<double>>>* relative_x) {
  const int nc = plate.dofs_per_node() * (plate.grid().ny() + 1);
  const auto num_sets = static_cast<std::size_t>(sets.num_sets());
  layouts->assign(static_cast<std::size_t>(num_sections), OutputLayout{});
  relative_x->assign(static_cast<std::size_t>(num_sections),
                     std::vector<std::vector<double>>(num_sets));
  for (OutputLayout& layout : *layouts) layout.positions.resize(num_sets);
  for (std::size_t set = 0; set < num_sets; ++set) {
    const CaseOutputs& o = outputs[static_cast<std::size_t>(sets.case_of_set[set])];
    for (std::size_t k = 0; k < o.x.size(); ++k) {
      int dofs[kMaxElementDofs];
      ElementVector row;
      plate.InterpolationRow(o.x[k], o.y, dofs, &row);
      const int section = dofs[0] / nc / intervals;
      (*layouts)[section].positions[set].push_back(static_cast<int>(k));
      const auto first_node =
          static_cast<std::size_t>(section) * static_cast<std::size_t>(intervals);
      (*relative_x)[section][set].push_back(o.x[k] - plate.grid().x[first_node]);
    }
  }
  for (OutputLayout& layout : *layouts) layout.Finish(sets);
}

SectionCondensation::SectionCondensation(const Plate& plate,
                                         int num_sections,
                                         int elements_per_section,
                                         int group_size,
                                         std::uint8_t fixed_mask_a,
                                         std::uint8_t fixed_mask_b,
                                         std::uint8_t start_mask,
                                         std::uint8_t end_mask,
                                         const Eigen::MatrixXd& loads,
                                         double frequency_hz,
                                         const std::vector<CaseOutputs>& outputs,
                                         bool always_pivot,
                                         bool higham,
                                         VectorKernels kernels)
    : num_sections_(num_sections),
      intervals_per_section_(elements_per_section * plate.element_order()),
      ny_(plate.grid().ny()),
      nc_(plate.dofs_per_node() * (plate.grid().ny() + 1)),
      fixed_mask_a_(fixed_mask_a),
      fixed_mask_b_(fixed_mask_b),
      start_mask_(start_mask),
      end_mask_(end_mask),
      num_cases_(static_cast<int>(loads.cols())),
      sets_(outputs),
      group_size_(group_size),
      always_pivot_(always_pivot),
      higham_(higham),
      kernels_(kernels) {
  const Grid& grid = plate.grid();
  // Node arithmetic below counts grid intervals: 2 per element at element order 2, whose
  // mid-side node lines are interior to their section like any other.
  const int intervals = intervals_per_section_;
  COMBABC_CHECK(grid.nx() == num_sections * intervals);
  COMBABC_CHECK(group_size >= 1 && num_sections % group_size == 0);
  COMBABC_CHECK(num_cases_ >= 1 && outputs.size() == static_cast<std::size_t>(num_cases_));
  COMBABC_CHECK(loads.rows() == static_cast<Eigen::Index>(grid.nx() + 1) * nc_);
  std::vector<std::vector<std::vector<double>>> relative_x;
  AssignOutputs(plate, num_sections, intervals, outputs, sets_, &section_layout_, &relative_x);
  for (int c = 0; c <= num_sections; ++c) {
    boundary_load_.push_back(loads.middleRows(static_cast<Eigen::Index>(c) * intervals * nc_, nc_)
                                 .cast<std::complex<double>>());
  }
  free_dofs_.resize(num_sections + 1);
  for (int c = 0; c <= num_sections; ++c) {
    for (int edges = 0; edges < 4; ++edges) {
      FreeDofs(c, (edges & 1) != 0, (edges & 2) != 0, &free_dofs_[c][edges]);
    }
  }
  // Sections made of the same element matrices (Plate shares them between elements of equal
  // size) have the same C in every clamp state, bit for bit: CondenseSections condenses each such
  // mesh once, whatever loads and outputs its sections have.
  const int elements = intervals / plate.element_order();
  const auto same_elements = [&](int s, int t) {
    for (int e = 0; e < elements; ++e) {
      for (int ey = 0; ey < plate.num_elements_y(); ++ey) {
        if (&plate.Element(s * elements + e, ey) != &plate.Element(t * elements + e, ey)) {
          return false;
        }
      }
    }
    return true;
  };
  mesh_of_section_.resize(num_sections);
  for (int s = 0; s < num_sections; ++s) {
    mesh_of_section_[s] = s;
    for (int t = 0; t < s && mesh_of_section_[s] == s; ++t) {
      if (mesh_of_section_[t] == t && same_elements(s, t)) mesh_of_section_[s] = t;
    }
  }
  // Sections with the same element sizes, no interior load in any case and outputs at the same
  // relative positions in every output set have identical pieces: compute those once.
  const double tol = 1e-12 * grid.x.back();
  const auto loaded = [&](int k) {
    return intervals > 1 && loads.middleRows((static_cast<Eigen::Index>(k) * intervals + 1) * nc_,
                                             static_cast<Eigen::Index>(intervals - 1) * nc_)
                                    .cwiseAbs()
                                    .maxCoeff() != 0.0;
  };
  const auto same_section = [&](int s, int t) {
    if (loaded(s) || loaded(t)) return false;
    for (int e = 0; e < intervals; ++e) {
      const double hs = grid.x[s * intervals + e + 1] - grid.x[s * intervals + e];
      const double ht = grid.x[t * intervals + e + 1] - grid.x[t * intervals + e];
      if (std::abs(hs - ht) > tol) return false;
    }
    for (std::size_t set = 0; set < relative_x[s].size(); ++set) {
      const std::vector<double>& a = relative_x[s][set];
      const std::vector<double>& b = relative_x[t][set];
      if (a.size() != b.size()) return false;
      for (std::size_t k = 0; k < a.size(); ++k) {
        if (std::abs(a[k] - b[k]) > tol) return false;
      }
    }
    return true;
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
    CondenseSections(plate, state, loads, frequency_hz, outputs, representatives);
  }
  // Groups made of the same section pieces with no load on their inner cross-sections are equal.
  const int num_groups = num_sections / group_size;
  const int group_states = 1 << (2 * group_size);
  group_piece_index_.assign(num_groups, std::vector<int>(group_states, -1));
  group_layout_.resize(num_groups);
  std::vector<Piece> composed;  // [group_piece_index_] -> the composed group pieces
  const auto same_group = [&](int g, int h) {
    // The first and last groups have the plate's end cross-sections folded in: never shared.
    const auto is_end = [&](int k) { return k == 0 || k == num_groups - 1; };
    if (is_end(g) || is_end(h)) return false;
    for (int k = 0; k < group_size; ++k) {
      if (piece_index_[g * group_size + k] != piece_index_[h * group_size + k]) return false;
      if (k > 0 && (boundary_load_[g * group_size + k].cwiseAbs().maxCoeff() != 0.0 ||
                    boundary_load_[h * group_size + k].cwiseAbs().maxCoeff() != 0.0)) {
        return false;
      }
    }
    return true;
  };
  for (int g = 0; g < num_groups; ++g) {
    OutputLayout& layout = group_layout_[g];
    layout.positions.resize(static_cast<std::size_t>(sets_.num_sets()));
    for (int k = 0; k < group_size; ++k) {
      const OutputLayout& section = section_layout_[g * group_size + k];
      for (std::size_t set = 0; set < layout.positions.size(); ++set) {
        const std::vector<int>& p = section.positions[set];
        layout.positions[set].insert(layout.positions[set].end(), p.begin(), p.end());
      }
    }
    layout.Finish(sets_);
    int twin = -1;
    for (int h = 0; h < g && twin < 0; ++h) {
      if (same_group(g, h)) twin = h;
    }
    for (int state = 0; state < group_states; ++state) {
      if (twin >= 0) {
        group_piece_index_[g][state] = group_piece_index_[twin][state];
      } else {
        group_piece_index_[g][state] = static_cast<int>(composed.size());
        composed.push_back(ComposeGroup(g, state));
      }
    }
  }
  // Jacobi scaling folded into the group pieces: every kept cross-section dof d is replaced by
  // u_d / s_d with s_d = |C_dd|^{-1/2} from one section piece. The BFS dofs (w, w_x, w_y, w_xy)
  // carry different units, and on the graded mesh the unscaled block system loses digits in the
  // unpivoted LDL^T; one scale vector for all cross-sections keeps the pieces shareable.
  const Eigen::MatrixXcd& reference = Condensed(pieces_[piece_index_[0][0]]);
  Eigen::VectorXd scale(nc_);
  for (int d = 0; d < nc_; ++d) {
    const double a = std::abs(reference(d, d));
    scale(d) = a > 0.0 ? 1.0 / std::sqrt(a) : 1.0;
  }
  for (Eigen::MatrixXcd& b : boundary_load_) b = scale.asDiagonal() * b;
  // The coupling between a group's two end cross-sections passes through 15 cm of strip, where
  // all but a few cross-section shapes have decayed: its singular values fall from O(1) to about
  // 1e-19 times the piece's largest entry. Keeping those above kRankTol times that entry (far below
  // the round-off of the condensation itself) makes the coupling a product of two nc x rank
  // factors (rank 5-8 at the default mesh), which the per-configuration solve exploits.
  constexpr double kRankTol = 1e-17;
  group_pieces_.reserve(composed.size());
  for (Piece& piece : composed) {
    Eigen::VectorXd s(piece.left_size + piece.right_size);
    if (piece.left_size > 0) s.head(nc_) = scale;
    if (piece.right_size > 0) s.tail(nc_) = scale;
    const Eigen::MatrixXcd condensed = s.asDiagonal() * piece.group_condensed * s.asDiagonal();
    SolvePiece out;
    out.left_size = piece.left_size;
    out.right_size = piece.right_size;
    out.load = s.asDiagonal() * piece.load;
    out.output_map = SplitMatrix(piece.output_map * s.asDiagonal());
    out.output_offset = piece.output_offset;
    out.singular = piece.singular;
    if (piece.left_size > 0) out.left_block = SplitMatrix(condensed.topLeftCorner(nc_, nc_));
    if (piece.right_size > 0) {
      out.right_block = SplitMatrix(condensed.bottomRightCorner(nc_, nc_));
    }
    if (piece.left_size > 0 && piece.right_size > 0) {
      const Eigen::MatrixXcd coupling = condensed.topRightCorner(nc_, nc_);
      const Eigen::BDCSVD<Eigen::MatrixXcd> svd(coupling,
                                                Eigen::ComputeFullU | Eigen::ComputeFullV);
      const double cutoff = kRankTol * condensed.cwiseAbs().maxCoeff();
      Eigen::Index rank = 0;
      while (rank < nc_ && svd.singularValues()(rank) > cutoff) ++rank;
      // coupling = U S V^H = (U S) (conj(V))^T.
      out.coupling_left =
          SplitMatrix(svd.matrixU().leftCols(rank) * svd.singularValues().head(rank).asDiagonal());
      out.coupling_right = SplitMatrix(svd.matrixV().leftCols(rank).conjugate());
    }
    group_pieces_.push_back(std::move(out));
    piece = Piece{};  // the composed piece is not needed any more: keep the peak low
  }
  // Only the group pieces are read per configuration. (Released last: released before the group
  // pieces are allocated, their memory would hold them, scattered, and the per-configuration
  // solve, which reads pieces all over the 20 MB, measured 15 % slower.)
  std::vector<Piece>().swap(pieces_);
  std::vector<Eigen::MatrixXcd>().swap(section_condensed_);
  std::vector<std::array<int, 4>>().swap(piece_index_);
  std::vector<OutputLayout>().swap(section_layout_);
  std::vector<int>().swap(mesh_of_section_);
}

SectionCondensation::Piece SectionCondensation::ComposeGroup(int group, int state) const {
  const int g = group_size_;
  const int nc = nc_;
  const int first = group * g;
  const auto section_state = [&](int k) { return (state >> (2 * k)) & 3; };
  // Group dofs z: cross-section t = 0..g of the group at [t nc, (t + 1) nc). The two ends are
  // kept (index into [left; right]) unless they are the plate's ends, which are folded in; inner
  // cross-sections keep their free dofs (interior).
  const bool fold_left = first == 0;
  const bool fold_right = first + g == num_sections_;
  const int left_size = fold_left ? 0 : nc;
  const int right_size = fold_right ? 0 : nc;
  const int nz = (g + 1) * nc;
  std::vector<int> boundary_index(nz, -1);
  std::vector<int> interior_index(nz, -1);
  for (int d = 0; d < nc; ++d) {
    if (!fold_left) boundary_index[d] = d;
    if (!fold_right) boundary_index[g * nc + d] = left_size + d;
  }
  int n_interior = 0;
  std::vector<int> free;
  std::vector<int> interior_cross_sections;
  for (int t = 0; t <= g; ++t) {
    if ((t == 0 && !fold_left) || (t == g && !fold_right)) continue;
    interior_cross_sections.push_back(t);
    const int left = t > 0 ? section_state(t - 1) : 0;
    const int right = t < g ? section_state(t) : 0;
    FreeDofs(first + t, ((left | right) & 1) != 0, ((left | right) & 2) != 0, &free);
    for (int d : free) interior_index[t * nc + d] = n_interior++;
  }
  const int nb = left_size + right_size;
  const int np = 2 * nc;  // a section piece's size
  const int cases = num_cases_;
  Eigen::MatrixXcd k_bb = Eigen::MatrixXcd::Zero(nb, nb);
  Eigen::MatrixXcd k_bi = Eigen::MatrixXcd::Zero(nb, n_interior);
  Eigen::MatrixXcd k_ib = Eigen::MatrixXcd::Zero(n_interior, nb);
  Eigen::MatrixXcd k_ii = Eigen::MatrixXcd::Zero(n_interior, n_interior);
  Eigen::MatrixXcd g_b = Eigen::MatrixXcd::Zero(nb, cases);
  Eigen::MatrixXcd g_i = Eigen::MatrixXcd::Zero(n_interior, cases);
  for (int k = 0; k < g; ++k) {
    const Piece& piece = pieces_[piece_index_[first + k][section_state(k)]];
    const Eigen::MatrixXcd& condensed = Condensed(piece);
    for (int c = 0; c < np; ++c) {
      const int zc = k * nc + c;  // the piece's [left; right] are cross-sections k and k + 1
      for (int r = 0; r < np; ++r) {
        const int zr = k * nc + r;
        const std::complex<double> v = condensed(r, c);
        if (boundary_index[zr] >= 0 && boundary_index[zc] >= 0) {
          k_bb(boundary_index[zr], boundary_index[zc]) += v;
        } else if (boundary_index[zr] >= 0 && interior_index[zc] >= 0) {
          k_bi(boundary_index[zr], interior_index[zc]) += v;
        } else if (interior_index[zr] >= 0 && boundary_index[zc] >= 0) {
          k_ib(interior_index[zr], boundary_index[zc]) += v;
        } else if (interior_index[zr] >= 0 && interior_index[zc] >= 0) {
          k_ii(interior_index[zr], interior_index[zc]) += v;
        }
      }
      if (boundary_index[zc] >= 0) g_b.row(boundary_index[zc]) += piece.load.row(c);
      if (interior_index[zc] >= 0) g_i.row(interior_index[zc]) += piece.load.row(c);
    }
  }
  for (int t : interior_cross_sections) {
    for (int d = 0; d < nc; ++d) {
      if (interior_index[t * nc + d] >= 0) {
        g_i.row(interior_index[t * nc + d]) += boundary_load_[first + t].row(d);
      }
    }
  }
  Eigen::MatrixXcd x_b = Eigen::MatrixXcd::Zero(n_interior, nb);
  Eigen::MatrixXcd x_f = Eigen::MatrixXcd::Zero(n_interior, cases);
  double singular = 0.0;
  if (n_interior > 0) {
    // Jacobi-scaled (see Plate::SolveHarmonic).
    const Eigen::VectorXd scale = k_ii.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
    const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(scale.asDiagonal() * k_ii * scale.asDiagonal());
    // Empty products are skipped: Eigen binds references to their (null) data in Debug.
    if (nb > 0) x_b = scale.asDiagonal() * lu.solve(scale.asDiagonal() * k_ib);
    // One load column at a time, each as the vector it was with a single case.
    for (int c = 0; c < cases; ++c) {
      const Eigen::VectorXcd scaled_load = scale.asDiagonal() * g_i.col(c);
      const Eigen::VectorXcd y = lu.solve(scaled_load);
      x_f.col(c) = scale.asDiagonal() * y;
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
  }
  Piece result;
  result.left_size = left_size;
  result.right_size = right_size;
  result.singular = singular;
  result.group_condensed = k_bb - k_bi * x_b;
  result.load.resize(nb, cases);
  for (int c = 0; c < cases && nb > 0; ++c) {
    const Eigen::VectorXcd x = x_f.col(c);
    result.load.col(c) = g_b.col(c) - k_bi * x;
  }
  // The outputs: map rows set after set, each set's rows section after section; offsets case
  // after case in the rows of the case's set (OutputLayout).
  const OutputLayout& layout = group_layout_[group];
  result.output_map = Eigen::MatrixXcd::Zero(layout.map_rows(), nb);
  result.output_offset = Eigen::VectorXcd::Zero(layout.offset_rows());
  for (int set = 0; set < sets_.num_sets(); ++set) {
    const std::vector<int>& set_cases = sets_.cases_of_set[set];
    int row = layout.map_begin[set];
    for (int k = 0; k < g; ++k) {
      const Piece& piece = pieces_[piece_index_[first + k][section_state(k)]];
      const OutputLayout& section = section_layout_[first + k];
      const auto rows = static_cast<int>(section.positions[set].size());
      for (int o = 0; o < rows; ++o, ++row) {
        const int t = row - layout.map_begin[set];  // the row within the set
        for (int c : set_cases) {
          result.output_offset(layout.offset_begin[c] + t) =
              piece.output_offset(section.offset_begin[c] + o);
        }
        for (int c = 0; c < np; ++c) {
          const int zc = k * nc + c;
          const std::complex<double> v = piece.output_map(section.map_begin[set] + o, c);
          if (boundary_index[zc] >= 0) {
            result.output_map(row, boundary_index[zc]) += v;
          } else if (interior_index[zc] >= 0) {
            // No kept end, no columns: a row of an empty matrix is null data plus an offset (UB).
            if (nb > 0) result.output_map.row(row) -= v * x_b.row(interior_index[zc]);
            for (int lc : set_cases) {
              result.output_offset(layout.offset_begin[lc] + t) += v * x_f(interior_index[zc], lc);
            }
          }
        }
      }
    }
  }
  return result;
}

void SectionCondensation::CondenseSections(const Plate& plate,
                                           int state,
                                           const Eigen::MatrixXd& loads,
                                           double frequency_hz,
                                           const std::vector<CaseOutputs>& outputs,
                                           const std::vector<int>& representatives) {
  const int m = intervals_per_section_;
  const int n_local = (m + 1) * nc_;
  const int elements = m / plate.element_order();
  // Classify local dofs: boundary (index into [left; right]), interior (index into I), or fixed.
  // The same for every section in this state.
  std::vector<int> boundary_index;
  std::vector<int> interior_index;
  const int n_interior = ClassifySectionDofs(
      m, nc_, ny_, state, fixed_mask_a_, fixed_mask_b_, &boundary_index, &interior_index);
  const int nb = 2 * nc_;
  const std::complex<double> mass_coefficient = plate.MassCoefficient(frequency_hz);
  const std::complex<double> i_unit(0.0, 1.0);
  for (std::size_t first = 0; first < representatives.size(); ++first) {
    const int mesh = mesh_of_section_[representatives[first]];
    bool seen = false;  // each mesh once, at its first distinct section
    for (std::size_t q = 0; q < first; ++q) {
      seen = seen || mesh_of_section_[representatives[q]] == mesh;
    }
    if (seen) continue;
    // The section matrices of the mesh (its first section: the others have the same elements).
    const int mesh_offset = mesh * m * nc_;
    Eigen::MatrixXcd s_bb = Eigen::MatrixXcd::Zero(nb, nb);
    Eigen::MatrixXcd s_ib = Eigen::MatrixXcd::Zero(n_interior, nb);
    std::vector<Eigen::Triplet<std::complex<double>>> triplets;
    for (int ex = mesh * elements; ex < (mesh + 1) * elements; ++ex) {
      for (int ey = 0; ey < plate.num_elements_y(); ++ey) {
        const ElementMatrices& e = plate.Element(ex, ey);
        const int ne = plate.element_dofs();
        int local[kMaxElementDofs];
        for (int k = 0; k < ne; ++k) local[k] = plate.ElementDof(ex, ey, k) - mesh_offset;
        for (int c = 0; c < ne; ++c) {
          for (int r = 0; r < ne; ++r) {
            const std::complex<double> v = e.stiffness_real(r, c) +
                                           i_unit * e.stiffness_imag(r, c) +
                                           mass_coefficient * e.mass_unit(r, c);
            const int rb = boundary_index[local[r]];
            const int cb = boundary_index[local[c]];
            const int ri = interior_index[local[r]];
            const int ci = interior_index[local[c]];
            if (rb >= 0 && cb >= 0) s_bb(rb, cb) += v;
            if (ri >= 0 && cb >= 0) s_ib(ri, cb) += v;
            if (ri >= 0 && ci >= 0) triplets.emplace_back(ri, ci, v);
          }
        }
      }
    }
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
    // S_BI = S_IB^T (complex symmetric: transpose, not adjoint).
    const int condensed = mesh * 4 + state;
    section_condensed_[condensed] = s_bb - s_ib.transpose() * x_b;
    // Each distinct section of this mesh: its loads and its outputs.
    for (std::size_t q = first; q < representatives.size(); ++q) {
      const int section = representatives[q];
      if (mesh_of_section_[section] != mesh) continue;
      const int offset = section * m * nc_;
      Piece& piece = pieces_[q * 4 + static_cast<std::size_t>(state)];
      piece.condensed = condensed;
      piece.left_size = nc_;
      piece.right_size = nc_;
      piece.load.resize(nb, num_cases_);
      Eigen::MatrixXcd x_f = Eigen::MatrixXcd::Zero(n_interior, num_cases_);
      for (int c = 0; c < num_cases_; ++c) {
        Eigen::VectorXcd f_interior = Eigen::VectorXcd::Zero(n_interior);
        for (int d = 0; d < n_local; ++d) {
          if (interior_index[d] >= 0) f_interior(interior_index[d]) = loads(offset + d, c);
        }
        Eigen::VectorXcd x = Eigen::VectorXcd::Zero(n_interior);
        if (n_interior > 0) x = scale.asDiagonal() * lu.solve(scale.asDiagonal() * f_interior);
        piece.load.col(c) = -s_ib.transpose() * x;
        x_f.col(c) = x;
      }
      const OutputLayout& layout = section_layout_[section];
      piece.output_map = Eigen::MatrixXcd::Zero(layout.map_rows(), nb);
      piece.output_offset = Eigen::VectorXcd::Zero(layout.offset_rows());
      for (int set = 0; set < sets_.num_sets(); ++set) {
        const CaseOutputs& o = outputs[static_cast<std::size_t>(sets_.case_of_set[set])];
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
              for (int c : sets_.cases_of_set[set]) {
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
  int state = 0;
  for (int k = 0; k < group_size_; ++k) {
    const int section = group * group_size_ + k;
    state |= ((clamps[section] != 0 ? 1 : 0) | (clamps[num_sections_ + section] != 0 ? 2 : 0))
             << (2 * k);
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
