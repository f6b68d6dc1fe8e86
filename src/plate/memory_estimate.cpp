// SensorOptions::EstimatedMemoryBytes: the precompute's peak memory, predicted from the options
// alone so that an oversized model is refused before anything is allocated. It mirrors what
// SectionCondensation keeps (docs/model.md, "Section condensation"): condensed pieces of the
// distinct sections (4 clamp states each) and of the distinct groups of sections (4^group_size
// states each), dense complex blocks of the cross-section size nc = 4 (ny + 1).
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "combabc/plate/sensor_model.hpp"

namespace combabc::plate {
namespace {

constexpr double kComplexBytes = 16.0;
// Bytes per plate dof for the load vector, dof maps and the sparse stiffness of a section.
constexpr double kBytesPerDof = 64.0;
// One set of element matrices (stiffness and mass, 16 x 16 doubles, and their workspace).
constexpr double kBytesPerElementKind = 4096.0;

}  // namespace

double SensorOptions::EstimatedMemoryBytes() const {
  const int sections = clamps_per_edge;
  // The same group size as SensorModel's constructor chooses.
  const int group_size = sections % 3 == 0 ? 3 : (sections % 2 == 0 ? 2 : 1);
  const int groups = sections / group_size;
  const double group_states = std::pow(4.0, group_size);
  const double nc = 4.0 * (elements_across_width + 1);
  const double piece_bytes = 4.0 * nc * nc * kComplexBytes;  // 2 nc x 2 nc, or its blocks
  const double output_row_bytes = 2.0 * nc * kComplexBytes;  // one output's map row

  // Sections touched by the load (a point load or a patch; clipping does not matter here).
  const double h = length / sections;
  const double patch = load_patch_length > 0.0 && load_patch_width > 0.0 ? load_patch_length : 0.0;
  auto loaded = [&](int s) {
    return load_x + 0.5 * patch >= s * h && load_x - 0.5 * patch <= (s + 1) * h;
  };
  // Outputs by section (relative position, rounded): what, besides the load, makes two sections'
  // condensed pieces differ.
  std::vector<std::vector<long long>> relative(static_cast<std::size_t>(sections));
  for (double x : output_positions) {
    const int s = std::clamp(static_cast<int>(x / h), 0, sections - 1);
    relative[s].push_back(std::llround((x - s * h) / h * 1e9));
  }
  std::vector<int> section_kind(static_cast<std::size_t>(sections));
  std::map<std::vector<long long>, int> section_kinds;
  double bytes = 0.0;
  for (int s = 0; s < sections; ++s) {
    std::vector<long long> signature = relative[s];
    if (loaded(s)) signature.push_back(-1 - s);  // a loaded section is unique
    const auto [it, inserted] =
        section_kinds.emplace(signature, static_cast<int>(section_kinds.size()));
    section_kind[s] = it->second;
    if (inserted) {
      bytes += 4.0 * (piece_bytes + static_cast<double>(relative[s].size()) * output_row_bytes);
    }
  }
  // Groups: the two end groups and loaded groups are unique, the others shared by signature.
  std::map<std::vector<int>, int> group_kinds;
  for (int g = 0; g < groups; ++g) {
    std::vector<int> signature;
    int outputs = 0;
    bool unique = g == 0 || g == groups - 1;
    for (int k = 0; k < group_size; ++k) {
      const int s = g * group_size + k;
      signature.push_back(section_kind[s]);
      outputs += static_cast<int>(relative[s].size());
      unique = unique || loaded(s);
    }
    if (unique) signature.push_back(-1 - g);
    if (group_kinds.emplace(signature, g).second) {
      bytes += group_states * (piece_bytes + outputs * output_row_bytes);
    }
  }
  // Transients, one at a time: condensing a section (dense interior-to-boundary maps and the
  // sparse LU of its interior) or composing a group (dense blocks of group_size - 1 interior
  // cross-sections).
  const double interior = (elements_per_section - 1) * nc;
  const double condense = 5.0 * interior * 2.0 * nc * kComplexBytes;
  const double compose = 24.0 * nc * nc * kComplexBytes * group_size * group_size;
  bytes += std::max(condense, compose);
  // The plate: dofs and the distinct element sizes of the graded mesh.
  const double dofs = nc * (static_cast<double>(sections) * elements_per_section + 1);
  // Integer halves on purpose: the graded mesh mirrors about the middle, so about half its
  // element sizes are distinct.
  const int distinct_along = elements_per_section / 2 + 1;
  const int distinct_across = elements_across_width / 2 + 1;
  const double element_kinds = static_cast<double>(distinct_along) * distinct_across;
  bytes += dofs * kBytesPerDof + element_kinds * kBytesPerElementKind;
  return bytes;
}

}  // namespace combabc::plate
