#pragma once
// The sectioned plate as both condensations see it (docs/model.md, "Section condensation" and
// "Continuous unknowns"): the clamp sections along x and their cross-sections, which dofs a
// cross-section keeps free in each clamp state, which section owns each output, and the loads on
// the cross-sections and inside the sections. Built once per model (SensorModel) and shared by
// the clamp-only condensation, its precompute cache and the continuous precomputes.
//
// The mesh has node lines on the section boundaries x_0 < ... < x_S, `intervals` grid intervals
// per section (2 per element at element order 2, whose mid-side node lines are cross-sections
// too). Cross-section c (c = 0..S) holds the nc = dofs_per_node (ny + 1) dofs of the node line at
// x_c, cross-section-major as the plate numbers them (plate.hpp).
#include <array>
#include <complex>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Dense>

#include "combabc/plate/assembly/clamp_pattern.hpp"
#include "combabc/plate/assembly/plate.hpp"

namespace combabc::plate {

// The masks that fix a cross-section's dofs (bit k of a mask: the node's dof k is fixed): an
// edge node of a fixed clamp (edge A at j = 0, edge B at j = ny) and the plate's two end
// cross-sections.
struct CrossSectionMasks {
  std::uint8_t fixed_a, fixed_b, start, end;
};

// Calls visit(e, r, c, local_r, local_c) for every entry (r, c) of every element matrix e of
// section `section` of `intervals` grid intervals, with the entry's local dofs (cross-section after
// cross-section from the section's start): the assembly loop the section condensations and the
// certification (higham_check.cpp) share. Always in the same order, so the sums it feeds are too.
template <class Visit>
void ForEachSectionEntry(const Plate& plate, int section, int intervals, Visit&& visit) {
  const int elements = intervals / plate.element_order();
  const int nc = plate.dofs_per_node() * (plate.grid().ny() + 1);
  const int offset = section * intervals * nc;
  const int ne = plate.element_dofs();
  for (int ex = section * elements; ex < (section + 1) * elements; ++ex) {
    for (int ey = 0; ey < plate.num_elements_y(); ++ey) {
      const ElementMatrices& e = plate.Element(ex, ey);
      int local[kMaxElementDofs];
      for (int k = 0; k < ne; ++k) local[k] = plate.ElementDof(ex, ey, k) - offset;
      for (int c = 0; c < ne; ++c) {
        for (int r = 0; r < ne; ++r) visit(e, r, c, local[r], local[c]);
      }
    }
  }
}

// One load case's outputs: w along the line y (m) at the positions x (m).
struct CaseOutputs {
  std::vector<double> x;
  double y = 0.0;
};

// The load cases' outputs grouped into output sets: cases with the same positions and line share
// one set, whose output maps both condensations condense once. The outputs of case c are
// w[first_output[c] + k] for its positions k (SensorOptions::OutputOffset).
struct OutputSets {
  std::vector<int> set_of_case;  // case -> its set
  std::vector<int> case_of_set;  // set -> the first case with it (its positions, line)
  std::vector<std::vector<int>> cases_of_set;  // set -> its cases, ascending
  std::vector<std::size_t> first_output;       // case -> its first output; [num cases] = the total
  explicit OutputSets(const std::vector<CaseOutputs>& outputs);
  int num_sets() const { return static_cast<int>(case_of_set.size()); }
  int num_cases() const { return static_cast<int>(set_of_case.size()); }
};

// Where the outputs of a section (or a group of sections) sit in its pieces: the output-map rows
// set after set, the output offsets case after case (each case has its set's rows, in the same
// order).
struct OutputLayout {
  std::vector<std::vector<int>> positions;  // [set] -> its positions here (indices), ascending
  std::vector<int> map_begin;               // [set] -> its first map row; [num sets] = the rows
  std::vector<int> offset_begin;            // [case] -> its first offset; [num cases] = the total
  // Fills map_begin and offset_begin from positions.
  void Finish(const OutputSets& sets);
  int map_rows() const { return map_begin.back(); }
  int offset_rows() const { return offset_begin.back(); }
  int rows_of_case(const OutputSets& sets, int c) const {
    return static_cast<int>(positions[sets.set_of_case[c]].size());
  }
};

class SectionLayout {
 public:
  // `plate` must have num_sections * elements_per_section elements along x (any element order).
  // `masks`: the dofs a fixed clamp fixes on its edge nodes and the short edges on the end
  // cross-sections. `loads`: one column per load case (the plate's load vectors); `outputs`: each
  // case's outputs.
  SectionLayout(const Plate& plate,
                int num_sections,
                int elements_per_section,
                const CrossSectionMasks& masks,
                Eigen::MatrixXd loads,
                std::vector<CaseOutputs> outputs);

  int num_sections() const { return num_sections_; }
  int intervals() const { return intervals_; }  // grid intervals per section
  int ny() const { return ny_; }
  int nc() const { return nc_; }  // dofs per cross-section
  int num_cases() const { return static_cast<int>(loads_.cols()); }
  const CrossSectionMasks& masks() const { return masks_; }

  // The free dofs (0..nc-1, ascending) of cross-section c when the nodes of edge A / edge B are
  // fixed as given (with the short edges' on the end cross-sections): tables built once.
  const std::vector<int>& FreeDofs(int c, bool fixed_a, bool fixed_b) const {
    return free_dofs_[c][(fixed_a ? 1 : 0) | (fixed_b ? 2 : 0)];
  }
  // The same in a configuration: a node on edge A (B) is fixed when either adjoining section
  // fixes it.
  const std::vector<int>& FreeDofs(int c, const ClampPattern& clamps) const {
    return FreeDofs(c,
                    clamps.BoundaryFixed(ClampPattern::kEdgeA, c),
                    clamps.BoundaryFixed(ClampPattern::kEdgeB, c));
  }
  // The local dofs of one section in clamp state `state` (bit 0 / bit 1: its edge-A / edge-B
  // clamp is fixed), (intervals + 1) cross-sections of nc: boundary[d] indexes [left; right] for
  // the first and last cross-sections, interior[d] the section's interior unknowns, -1 otherwise
  // (a dof fixed by a clamp). Returns the interior count.
  int ClassifySectionDofs(int state, std::vector<int>* boundary, std::vector<int>* interior) const;

  // Sections made of the same element matrices (Plate shares them between elements of equal
  // size): section -> the first section with its mesh.
  int MeshOfSection(int s) const { return mesh_of_section_[s]; }
  // Whether sections s and t have the same element lengths (to 1e-12 of the plate's length).
  bool SameSpacing(int s, int t) const;
  // Whether their outputs sit at the same positions relative to their starts in every output set
  // (to the same tolerance).
  bool SameOutputPositions(int s, int t) const;
  // Whether some case's load reaches the interior of section s.
  bool InteriorLoaded(int s) const { return interior_loaded_[s] != 0; }

  const std::vector<CaseOutputs>& outputs() const { return outputs_; }
  const OutputSets& sets() const { return sets_; }
  // The outputs of section s (each output belongs to the section of the element that holds it:
  // an output on a section boundary depends only on that cross-section's dofs, so either
  // neighbour is exact).
  const OutputLayout& SectionOutputs(int s) const { return section_outputs_[s]; }

  const Eigen::MatrixXd& loads() const { return loads_; }
  // The loads on cross-section c (nc x cases), unscaled.
  const Eigen::MatrixXcd& BoundaryLoad(int c) const { return boundary_load_[c]; }

 private:
  int num_sections_;
  int intervals_;
  int ny_;
  int nc_;
  CrossSectionMasks masks_;
  // [cross-section][edge A fixed | edge B fixed << 1] -> its free dofs.
  std::vector<std::array<std::vector<int>, 4>> free_dofs_;
  std::vector<int> mesh_of_section_;
  std::vector<double> spacing_;  // grid interval lengths along x
  double tol_;
  std::vector<char> interior_loaded_;  // [section]
  std::vector<CaseOutputs> outputs_;
  OutputSets sets_;
  std::vector<OutputLayout> section_outputs_;                 // [section]
  std::vector<std::vector<std::vector<double>>> relative_x_;  // [section][set]
  Eigen::MatrixXd loads_;
  std::vector<Eigen::MatrixXcd> boundary_load_;  // [cross-section]
};

// The Jacobi scale of the cross-section dofs, s_d = |C_dd|^{-1/2} from the diagonal of a
// reference section piece (1 where it is 0): every kept cross-section dof d is replaced by
// u_d / s_d. The BFS dofs (w, w_x, w_y, w_xy) carry different units, and on the graded mesh the
// unscaled block system loses digits in the unpivoted LDL^T; one scale vector for all
// cross-sections keeps the pieces shareable.
Eigen::VectorXd CrossSectionScale(const Eigen::MatrixXcd& reference, int nc);

}  // namespace combabc::plate
