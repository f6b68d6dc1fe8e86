// SensorOptions::EstimatedMemoryBytes: the precompute's peak memory, predicted from the options
// alone so that an oversized model is refused before anything is allocated. It mirrors what
// SectionCondensation keeps (docs/model.md, "Section condensation"): condensed pieces of the
// distinct sections (4 clamp states each) and of the distinct groups of sections (4^group_size
// states each), dense complex blocks of the cross-section size nc = n (ny + 1), n dofs per node.
// SensorOptions::EstimatedContinuousMemoryBytes: the same for what ContinuousCondensation keeps
// and builds (docs/model.md, "Continuous unknowns"). Several load cases share the pieces (one C
// per mesh and clamp state, one output map per output set); what each case adds is its load
// columns and output offsets, and the pieces of the sections and groups its load makes unique
// (docs/model.md, "Several load cases").
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "combabc/plate/sensor_model.hpp"
#include "plate/fast_path/continuous_condensation.hpp"

namespace combabc::plate {
namespace {

constexpr double kComplexBytes = 16.0;
// Bytes per plate dof for the load vector, dof maps and the sparse stiffness of a section.
constexpr double kBytesPerDof = 64.0;
// One set of element matrices (stiffness, mass and rotary inertia: four matrices of at most
// 45 x 45 doubles stored inline whatever the family, kMaxElementDofs, and their workspace).
constexpr double kBytesPerElementKind = 81920.0;

// Whether section s is touched by the load of case c (a point load or a patch; clipping does
// not matter).
bool Loaded(const SensorOptions& o, const LoadCase& c, int s) {
  const double h = o.length / o.clamps_per_edge;
  const double patch =
      c.load_patch_length > 0.0 && c.load_patch_width > 0.0 ? c.load_patch_length : 0.0;
  return c.load_x + 0.5 * patch >= s * h && c.load_x - 0.5 * patch <= (s + 1) * h;
}

bool LoadedByAny(const SensorOptions& o, int s) {
  for (const LoadCase& c : o.load_cases) {
    if (Loaded(o, c, s)) return true;
  }
  return false;
}

// The outputs of one section or group: output-map rows (one per position of each output set)
// and output offsets (one per position of each case).
struct OutputCount {
  int map_rows = 0;
  int offsets = 0;
};

// The distinct sections, as both condensations share their pieces: the same outputs at the same
// relative positions in every output set (cases with equal positions and line share one) and no
// load from any case (a loaded section is unique). Returns each section's kind and fills the
// outputs of each section.
std::vector<int> SectionKinds(const SensorOptions& o,
                              std::vector<OutputCount>* outputs,
                              int* kinds) {
  const int sections = o.clamps_per_edge;
  const double h = o.length / sections;
  // Output sets: the first case with each (positions, line), and each case's set.
  std::vector<std::size_t> set_case;
  std::vector<std::size_t> set_of;
  for (std::size_t c = 0; c < o.load_cases.size(); ++c) {
    const LoadCase& lc = o.load_cases[c];
    std::size_t set = set_case.size();
    for (std::size_t k = 0; k < set_case.size() && set == set_case.size(); ++k) {
      const LoadCase& other = o.load_cases[set_case[k]];
      if (other.output_positions == lc.output_positions &&
          other.output_y_fraction == lc.output_y_fraction) {
        set = k;
      }
    }
    if (set == set_case.size()) set_case.push_back(c);
    set_of.push_back(set);
  }
  std::vector<std::vector<long long>> relative(static_cast<std::size_t>(sections));
  std::vector<std::vector<int>> per_set(static_cast<std::size_t>(sections),
                                        std::vector<int>(set_case.size(), 0));
  for (std::size_t set = 0; set < set_case.size(); ++set) {
    for (std::size_t s = 0; s < relative.size(); ++s) relative[s].push_back(-1);  // separator
    for (double x : o.load_cases[set_case[set]].output_positions) {
      const int s = std::clamp(static_cast<int>(x / h), 0, sections - 1);
      relative[s].push_back(std::llround((x - s * h) / h * 1e9));
      ++per_set[s][set];
    }
  }
  std::vector<int> section_kind(static_cast<std::size_t>(sections));
  std::map<std::vector<long long>, int> section_kinds;
  outputs->assign(static_cast<std::size_t>(sections), OutputCount{});
  for (int s = 0; s < sections; ++s) {
    std::vector<long long> signature = relative[s];
    if (LoadedByAny(o, s)) signature.push_back(-2 - s);
    section_kind[s] =
        section_kinds.emplace(signature, static_cast<int>(section_kinds.size())).first->second;
    for (int n : per_set[s]) (*outputs)[s].map_rows += n;
    for (std::size_t set : set_of) (*outputs)[s].offsets += per_set[s][set];
  }
  *kinds = static_cast<int>(section_kinds.size());
  return section_kind;
}

}  // namespace

double SensorOptions::EstimatedMemoryBytes() const {
  const int sections = clamps_per_edge;
  const auto cases = static_cast<double>(load_cases.size());
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
  // What depends on the loads and outputs: the map rows, each case's offsets and load column.
  const auto case_bytes = [&](const OutputCount& n) {
    return n.map_rows * output_row_bytes + n.offsets * kComplexBytes +
           cases * 2.0 * nc * kComplexBytes;
  };

  std::vector<OutputCount> outputs_of;
  int num_kinds = 0;
  const std::vector<int> section_kind = SectionKinds(*this, &outputs_of, &num_kinds);
  // Section pieces: C once per mesh and clamp state (every section of the sensor's grid has the
  // same graded mesh: one), the loads and outputs per distinct section.
  double bytes = 4.0 * piece_bytes;
  std::vector<bool> counted(static_cast<std::size_t>(num_kinds), false);
  for (int s = 0; s < sections; ++s) {
    if (counted[section_kind[s]]) continue;
    counted[section_kind[s]] = true;
    bytes += 4.0 * case_bytes(outputs_of[s]);
  }
  // Groups: the two end groups and loaded groups are unique, the others shared by signature.
  std::map<std::vector<int>, int> group_kinds;
  for (int g = 0; g < groups; ++g) {
    std::vector<int> signature;
    OutputCount outputs;
    bool unique = g == 0 || g == groups - 1;
    for (int k = 0; k < group_size; ++k) {
      const int s = g * group_size + k;
      signature.push_back(section_kind[s]);
      outputs.map_rows += outputs_of[s].map_rows;
      outputs.offsets += outputs_of[s].offsets;
      unique = unique || LoadedByAny(*this, s);
    }
    if (unique) signature.push_back(-1 - g);
    if (group_kinds.emplace(signature, g).second) {
      bytes += group_states * (piece_bytes + case_bytes(outputs));
    }
  }
  // Transients, one at a time: condensing a section (dense interior-to-boundary maps and the
  // sparse LU of its interior) or composing a group (dense blocks of group_size - 1 interior
  // cross-sections).
  const double interior = (along - 1) * nc;
  const double condense = 5.0 * interior * 2.0 * nc * kComplexBytes;
  const double compose = 24.0 * nc * nc * kComplexBytes * group_size * group_size;
  bytes += std::max(condense, compose);
  // The plate: dofs (and the load matrix, a column per case) and the distinct element sizes of
  // the graded mesh.
  const double dofs = nc * (static_cast<double>(sections) * along + 1);
  // Integer halves on purpose: the graded mesh mirrors about the middle, so about half its
  // element sizes are distinct.
  const int distinct_along = elements_per_section / 2 + 1;
  const int distinct_across = ElementsAcrossWidth() / 2 + 1;
  const double element_kinds = static_cast<double>(distinct_along) * distinct_across;
  bytes += dofs * (kBytesPerDof + 8.0 * cases) + element_kinds * kBytesPerElementKind;
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

  std::vector<OutputCount> outputs_of;
  int num_kinds = 0;
  const std::vector<int> section_kind = SectionKinds(*this, &outputs_of, &num_kinds);
  double section_tables = 0.0, section_kept = 0.0, section_transient = 0.0;
  std::vector<bool> counted(static_cast<std::size_t>(num_kinds), false);
  const double h = length / clamps_per_edge;
  for (int s = 0; s < clamps_per_edge; ++s) {
    if (counted[section_kind[s]]) continue;
    counted[section_kind[s]] = true;
    // The output maps of its output sets; for each case whose load touches it, that case's load,
    // its output offsets and its interior load vector.
    const double n_out = outputs_of[s].map_rows;
    double load_rows = 0.0;
    double loaded_cases = 0.0;
    for (const LoadCase& c : load_cases) {
      if (!Loaded(*this, c, s)) continue;
      double rows = 0.0;
      for (double x : c.output_positions) {
        rows += std::clamp(static_cast<int>(x / h), 0, clamps_per_edge - 1) == s ? 1.0 : 0.0;
      }
      load_rows += nb + rows;
      loaded_cases += 1.0;
    }
    section_tables += 4.0 * (n_out * nb + load_rows) * (terms + 1.0) * real_bytes * table_parts;
    section_kept += 4.0 * (n_out * interior + n_out * nb + interior * loaded_cases) * kComplexBytes;
    section_transient += 4.0 * (n_out * nb + load_rows) * (terms + 1.0) * kComplexBytes;
  }
  const double boundary_loads =
      (clamps_per_edge + 1.0) * nc * kComplexBytes * static_cast<double>(load_cases.size());
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
