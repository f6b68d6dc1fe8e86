// SensorOptions::EstimatedMemoryBytes: the precompute's peak memory, predicted from the options
// alone so that an oversized model is refused before anything is allocated. It mirrors what
// SectionCondensation keeps (docs/model.md, "Section condensation"): condensed pieces of the
// distinct sections (4 clamp states each) and of the distinct groups of sections (4^group_size
// states each), dense complex blocks of the cross-section size nc = n (ny + 1), n dofs per node.
// SensorOptions::EstimatedContinuousMemoryBytes: the same for what ContinuousCondensation keeps
// and builds (docs/model.md, "Continuous unknowns").
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "combabc/plate/sensor_model.hpp"
#include "continuous_condensation.hpp"

namespace combabc::plate {
namespace {

constexpr double kComplexBytes = 16.0;
// Bytes per plate dof for the load vector, dof maps and the sparse stiffness of a section.
constexpr double kBytesPerDof = 64.0;
// One set of element matrices (stiffness, mass and rotary inertia: four matrices of at most
// 45 x 45 doubles stored inline whatever the family, kMaxElementDofs, and their workspace).
constexpr double kBytesPerElementKind = 81920.0;

// Whether section s is touched by the load (a point load or a patch; clipping does not matter).
bool Loaded(const SensorOptions& o, int s) {
  const double h = o.length / o.clamps_per_edge;
  const LoadCase& c = o.load_cases.front();
  const double patch =
      c.load_patch_length > 0.0 && c.load_patch_width > 0.0 ? c.load_patch_length : 0.0;
  return c.load_x + 0.5 * patch >= s * h && c.load_x - 0.5 * patch <= (s + 1) * h;
}

// The distinct sections, as both condensations share their pieces: the same outputs at the same
// relative positions and no load (a loaded section is unique). Returns each section's kind and
// fills the number of outputs of each section.
std::vector<int> SectionKinds(const SensorOptions& o, std::vector<int>* outputs, int* kinds) {
  const int sections = o.clamps_per_edge;
  const double h = o.length / sections;
  std::vector<std::vector<long long>> relative(static_cast<std::size_t>(sections));
  for (double x : o.load_cases.front().output_positions) {
    const int s = std::clamp(static_cast<int>(x / h), 0, sections - 1);
    relative[s].push_back(std::llround((x - s * h) / h * 1e9));
  }
  std::vector<int> section_kind(static_cast<std::size_t>(sections));
  std::map<std::vector<long long>, int> section_kinds;
  outputs->assign(static_cast<std::size_t>(sections), 0);
  for (int s = 0; s < sections; ++s) {
    std::vector<long long> signature = relative[s];
    if (Loaded(o, s)) signature.push_back(-1 - s);
    section_kind[s] =
        section_kinds.emplace(signature, static_cast<int>(section_kinds.size())).first->second;
    (*outputs)[s] = static_cast<int>(relative[s].size());
  }
  *kinds = static_cast<int>(section_kinds.size());
  return section_kind;
}

}  // namespace

double SensorOptions::EstimatedMemoryBytes() const {
  if (load_cases.size() > 1) {
    // Each load case is condensed on its own.
    double bytes = 0.0;
    for (const LoadCase& c : load_cases) {
      SensorOptions one = *this;
      one.load_cases = {c};
      bytes += one.EstimatedMemoryBytes();
    }
    return bytes;
  }
  const int sections = clamps_per_edge;
  // The same group size as SensorModel's constructor chooses.
  const int group_size = sections % 3 == 0 ? 3 : (sections % 2 == 0 ? 2 : 1);
  const int groups = sections / group_size;
  const double group_states = std::pow(4.0, group_size);
  // Grid intervals: 2 per element at element order 2 (the mid-side node lines).
  const int along = ElementOrder() * elements_per_section;
  const int across = ElementOrder() * ElementsAcrossWidth();
  const double nc = DofsPerNode(theory) * (across + 1.0);
  const double piece_bytes = 4.0 * nc * nc * kComplexBytes;  // 2 nc x 2 nc, or its blocks
  const double output_row_bytes = 2.0 * nc * kComplexBytes;  // one output's map row

  std::vector<int> outputs_of;
  int num_kinds = 0;
  const std::vector<int> section_kind = SectionKinds(*this, &outputs_of, &num_kinds);
  double bytes = 0.0;
  std::vector<bool> counted(static_cast<std::size_t>(num_kinds), false);
  for (int s = 0; s < sections; ++s) {
    if (counted[section_kind[s]]) continue;
    counted[section_kind[s]] = true;
    bytes += 4.0 * (piece_bytes + static_cast<double>(outputs_of[s]) * output_row_bytes);
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
      outputs += outputs_of[s];
      unique = unique || Loaded(*this, s);
    }
    if (unique) signature.push_back(-1 - g);
    if (group_kinds.emplace(signature, g).second) {
      bytes += group_states * (piece_bytes + outputs * output_row_bytes);
    }
  }
  // Transients, one at a time: condensing a section (dense interior-to-boundary maps and the
  // sparse LU of its interior) or composing a group (dense blocks of group_size - 1 interior
  // cross-sections).
  const double interior = (along - 1) * nc;
  const double condense = 5.0 * interior * 2.0 * nc * kComplexBytes;
  const double compose = 24.0 * nc * nc * kComplexBytes * group_size * group_size;
  bytes += std::max(condense, compose);
  // The plate: dofs and the distinct element sizes of the graded mesh.
  const double dofs = nc * (static_cast<double>(sections) * along + 1);
  // Integer halves on purpose: the graded mesh mirrors about the middle, so about half its
  // element sizes are distinct.
  const int distinct_along = elements_per_section / 2 + 1;
  const int distinct_across = ElementsAcrossWidth() / 2 + 1;
  const double element_kinds = static_cast<double>(distinct_along) * distinct_across;
  bytes += dofs * kBytesPerDof + element_kinds * kBytesPerElementKind;
  return bytes;
}

double SensorOptions::EstimatedContinuousMemoryBytes(bool loss_factor_unknown) const {
  // One set of section pieces in complex arithmetic unless K_base is real: a loss factor among
  // the unknowns, or layers whose imaginary bending stiffness is proportional to the real one
  // (one loss factor, or one Poisson ratio, across the layers; SensorModel's constructor).
  bool one_loss_factor = true, one_poisson_ratio = true;
  for (const Layer& layer : layers) {
    one_loss_factor = one_loss_factor && layer.loss_factor == layers.front().loss_factor;
    one_poisson_ratio = one_poisson_ratio && layer.poisson_ratio == layers.front().poisson_ratio;
  }
  // In FSDT and RZT one Poisson ratio is not enough: the shear (and RZT's zigzag) stiffnesses
  // weight the loss factors by their own energies, not the bending energy.
  const bool proportional =
      one_loss_factor || (one_poisson_ratio && theory == PlateTheory::kKirchhoff);
  const double table_parts = loss_factor_unknown || proportional ? 1.0 : 2.0;
  const double real_bytes = 8.0;
  const int along = ElementOrder() * elements_per_section;  // grid intervals, as above
  const double nc = DofsPerNode(theory) * (ElementOrder() * ElementsAcrossWidth() + 1.0);
  const double nb = 2.0 * nc;  // a section's two end cross-sections
  // Interior dofs (an upper bound: clamped edge dofs are removed) and their sparse matrices: a
  // node couples with at most 9 nodes x 4 dofs (25 nodes x its dofs at element order 2); entry
  // and row index, plus the column starts.
  const double interior = (along - 1) * nc;
  const double couplings = ElementOrder() == 2 ? 25.0 * DofsPerNode(theory) : 36.0;
  const double sparse = interior * couplings * (kComplexBytes + 4.0) + (interior + 1.0) * 4.0;
  const double terms =
      interior > 0.0 ? ContinuousCondensation::TermsFor(ContinuousCondensation::kMaxRatio) : 0.0;
  const double packed = nc * (nc + 1.0) + nc * nc;  // a packed piece's entries

  // Every section has the same graded mesh: one mesh in 4 clamp states.
  const double state_tables = 4.0 * packed * (terms + 2.0) * real_bytes * table_parts;
  const double state_kept =
      4.0 * (2.0 * interior * nb * kComplexBytes + 2.0 * nb * nb * kComplexBytes + 2.0 * sparse);
  // Built before the tables: K_G, M_G and the moments T_k, full complex nb x nb.
  const double state_transient = 4.0 * (terms + 2.0) * nb * nb * kComplexBytes;

  std::vector<int> outputs_of;
  int num_kinds = 0;
  const std::vector<int> section_kind = SectionKinds(*this, &outputs_of, &num_kinds);
  double section_tables = 0.0, section_kept = 0.0, section_transient = 0.0;
  std::vector<bool> counted(static_cast<std::size_t>(num_kinds), false);
  for (int s = 0; s < clamps_per_edge; ++s) {
    if (counted[section_kind[s]]) continue;
    counted[section_kind[s]] = true;
    const double n_out = outputs_of[s];
    const double load_rows = Loaded(*this, s) ? nb + n_out : 0.0;
    section_tables += 4.0 * (n_out * nb + load_rows) * (terms + 1.0) * real_bytes * table_parts;
    section_kept += 4.0 * (n_out * interior + n_out * nb + interior) * kComplexBytes;
    section_transient += 4.0 * (n_out * nb + load_rows) * (terms + 1.0) * kComplexBytes;
  }
  const double boundary_loads = (clamps_per_edge + 1.0) * nc * kComplexBytes;
  const double kept = state_tables + state_kept + section_tables + section_kept + boundary_loads;
  // The peak: everything but the tables, with the series terms they are built from, one complex
  // table being split, and one interior solve (its sparse LU and X0 = -K_II^-1 K_IB).
  const double one_table = packed * (terms + 2.0) * kComplexBytes;
  const double solve = 5.0 * interior * nb * kComplexBytes;
  const double peak = kept - state_tables - section_tables + state_transient + section_transient +
                      one_table + solve;
  return std::max(kept, peak);
}

}  // namespace combabc::plate
