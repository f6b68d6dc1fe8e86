#include "plate/fast_path/section_layout.hpp"

#include <cmath>
#include <utility>

#include "combabc/core/check.hpp"

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

SectionLayout::SectionLayout(const Plate& plate,
                             int num_sections,
                             int elements_per_section,
                             const CrossSectionMasks& masks,
                             Eigen::MatrixXd loads,
                             std::vector<CaseOutputs> outputs)
    : num_sections_(num_sections),
      intervals_(elements_per_section * plate.element_order()),
      ny_(plate.grid().ny()),
      nc_(plate.dofs_per_node() * (plate.grid().ny() + 1)),
      masks_(masks),
      tol_(1e-12 * plate.grid().x.back()),
      outputs_(std::move(outputs)),
      sets_(outputs_),
      loads_(std::move(loads)) {
  const Grid& grid = plate.grid();
  const int m = intervals_;
  COMBABC_CHECK(grid.nx() == num_sections * m);
  COMBABC_CHECK(loads_.cols() >= 1 && outputs_.size() == static_cast<std::size_t>(loads_.cols()));
  COMBABC_CHECK(loads_.rows() == static_cast<Eigen::Index>(grid.nx() + 1) * nc_);
  // Free dofs: a fixed clamp fixes its edge's nodes by its mask, the short edges every node of
  // the first and last cross-sections by theirs.
  const int dofs_per_node = plate.dofs_per_node();
  free_dofs_.resize(num_sections + 1);
  for (int c = 0; c <= num_sections; ++c) {
    for (int edges = 0; edges < 4; ++edges) {
      for (int d = 0; d < nc_; ++d) {
        const int j = d / dofs_per_node;
        const int bit = 1 << (d % dofs_per_node);
        int mask = 0;
        if ((edges & 1) != 0 && j == 0) mask |= masks.fixed_a;
        if ((edges & 2) != 0 && j == ny_) mask |= masks.fixed_b;
        if (c == 0) mask |= masks.start;
        if (c == num_sections) mask |= masks.end;
        if ((mask & bit) == 0) free_dofs_[c][edges].push_back(d);
      }
    }
  }
  const int elements = m / plate.element_order();
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
  for (int i = 0; i < grid.nx(); ++i) spacing_.push_back(grid.x[i + 1] - grid.x[i]);
  for (int s = 0; s < num_sections; ++s) {
    interior_loaded_.push_back(m > 1 &&
                               loads_.middleRows((static_cast<Eigen::Index>(s) * m + 1) * nc_,
                                                 static_cast<Eigen::Index>(m - 1) * nc_)
                                       .cwiseAbs()
                                       .maxCoeff() != 0.0);
  }
  for (int c = 0; c <= num_sections; ++c) {
    boundary_load_.push_back(loads_.middleRows(static_cast<Eigen::Index>(c) * m * nc_, nc_)
                                 .cast<std::complex<double>>());
  }
  // The outputs' sections, and their positions relative to the section's start.
  const auto num_sets = static_cast<std::size_t>(sets_.num_sets());
  section_outputs_.assign(static_cast<std::size_t>(num_sections), OutputLayout{});
  relative_x_.assign(static_cast<std::size_t>(num_sections),
                     std::vector<std::vector<double>>(num_sets));
  for (OutputLayout& layout : section_outputs_) layout.positions.resize(num_sets);
  for (std::size_t set = 0; set < num_sets; ++set) {
    const CaseOutputs& o = outputs_[static_cast<std::size_t>(sets_.case_of_set[set])];
    for (std::size_t k = 0; k < o.x.size(); ++k) {
      int dofs[kMaxElementDofs];
      ElementVector row;
      plate.InterpolationRow(o.x[k], o.y, dofs, &row);
      const int section = dofs[0] / nc_ / m;
      section_outputs_[section].positions[set].push_back(static_cast<int>(k));
      const auto first_node = static_cast<std::size_t>(section) * static_cast<std::size_t>(m);
      relative_x_[section][set].push_back(o.x[k] - grid.x[first_node]);
    }
  }
  for (OutputLayout& layout : section_outputs_) layout.Finish(sets_);
}

int SectionLayout::ClassifySectionDofs(int state,
                                       std::vector<int>* boundary,
                                       std::vector<int>* interior) const {
  const int m = intervals_;
  const int nc = nc_;
  const int ny = ny_;
  const int n_local = (m + 1) * nc;
  const bool fixed_a = (state & 1) != 0;
  const bool fixed_b = (state & 2) != 0;
  const int dofs_per_node = nc / (ny + 1);
  boundary->assign(n_local, -1);
  interior->assign(n_local, -1);
  int n_interior = 0;
  for (int d = 0; d < n_local; ++d) {
    if (d < nc) {
      (*boundary)[d] = d;
    } else if (d >= m * nc) {
      (*boundary)[d] = d - (m - 1) * nc;
    } else {
      const int j = (d / dofs_per_node) % (ny + 1);
      const int bit = 1 << (d % dofs_per_node);
      const bool fixed = (fixed_a && j == 0 && (masks_.fixed_a & bit)) ||
                         (fixed_b && j == ny && (masks_.fixed_b & bit));
      if (!fixed) (*interior)[d] = n_interior++;
    }
  }
  return n_interior;
}

bool SectionLayout::SameSpacing(int s, int t) const {
  const int m = intervals_;
  for (int e = 0; e < m; ++e) {
    if (std::abs(spacing_[s * m + e] - spacing_[t * m + e]) > tol_) return false;
  }
  return true;
}

bool SectionLayout::SameOutputPositions(int s, int t) const {
  for (std::size_t set = 0; set < relative_x_[s].size(); ++set) {
    const std::vector<double>& a = relative_x_[s][set];
    const std::vector<double>& b = relative_x_[t][set];
    if (a.size() != b.size()) return false;
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (std::abs(a[k] - b[k]) > tol_) return false;
    }
  }
  return true;
}

Eigen::VectorXd CrossSectionScale(const Eigen::MatrixXcd& reference, int nc) {
  Eigen::VectorXd scale(nc);
  for (int d = 0; d < nc; ++d) {
    const double a = std::abs(reference(d, d));
    scale(d) = a > 0.0 ? 1.0 / std::sqrt(a) : 1.0;
  }
  return scale;
}

}  // namespace combabc::plate
