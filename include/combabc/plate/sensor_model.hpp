#pragma once
// The built-in simulator of the paper's fibre-optic sensor (Shamas et al. 2024, section 4): a
// layered strip with 36 switchable clamp sections along its long edges, driven harmonically, whose
// output is the displacement amplitude |w| along the top centreline. Every default below is a
// stated assumption (docs/model.md, "Defaults"); the paper gives none of the dimensions except the
// 90 cm length, the 18 + 18 clamp sections of 5 cm, the 0.04 N load at 45 cm and 5 Hz.
//
// Fast re-analysis (docs/model.md, "Section condensation"): each clamp section's interior is
// condensed onto its two end cross-sections once for each of its 4 (edge A, edge B) clamp states,
// groups of 3 sections are composed for each of their 64 states, and a configuration then costs
// one block-tridiagonal solve over the 5 inner group boundaries. This is exact: it equals the
// full sparse solve of the same mesh to round-off (tests: < 1e-10 relative at the default mesh).
//
// Continuous unknowns (docs/model.md, "Continuous unknowns"): a call may also change the
// foundation stiffness, a scale of the laminate's stiffness and one loss factor for all layers
// (SensorVariation). Those change every section piece, so that path evaluates the pieces per call
// from a precompute split by physics (a power series in one complex number, or a direct
// condensation where it would converge slowly) and solves the chain of section boundaries. It is
// exact: it equals the full solve of a model built with the same values up to round-off amplified
// by the conditioning (tests: < 1e-9 relative at the test mesh; docs/model.md for the default one).
#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Dense>

#include "combabc/core/thread_pool.hpp"
#include "combabc/plate/assembly/clamp_pattern.hpp"
#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/elements/laminate.hpp"
#include "combabc/plate/fast_path/vector_kernels.hpp"

namespace combabc::plate {

class SectionLayout;           // src/plate/fast_path/section_layout.hpp
struct CaseOutputs;            // src/plate/fast_path/section_layout.hpp
class SectionCondensation;     // src/plate/fast_path/section_condensation.hpp
class ContinuousCondensation;  // src/plate/fast_path/continuous_condensation.hpp
struct ContinuousCache;        // src/plate/fast_path/continuous_condensation.hpp

// Default laminate, bottom to top (assumptions, docs/model.md): a soft polyurethane base, an
// elastomer core carrying the fibre, a polyurethane cover.
std::vector<Layer> DefaultSensorLayers();
// 0, 0.01, ..., 0.90 m: the paper's LDV grid extended over the whole length.
std::vector<double> DefaultOutputPositions();

// Size maxima (docs/config.md, "Limits"). Each is far above any useful sensor model; the binding
// limit is usually SensorOptions::memory_limit_bytes, which EstimatedMemoryBytes() checks.
inline constexpr int kMaxClampsPerEdge = 1000;
inline constexpr int kMaxElementsPerSection = 1000;
inline constexpr int kMaxElementsAcrossWidth = 1000;
inline constexpr std::size_t kMaxOutputPositions = 100000;
// Default memory budget of a model: 4 GB (10^9 bytes each, as messages print them).
inline constexpr double kDefaultMemoryLimitBytes = 4e9;

// Most load cases in one model (docs/config.md, "Limits"): a design grid is tens of candidates.
inline constexpr std::size_t kMaxLoadCases = 1000;

struct SensorOptions;

// One experiment's load and scan line on the sensor.
struct LoadCase {
  // Harmonic load: amplitude `load_force` at (load_x, load_y_fraction * width), as a uniform
  // pressure on a load_patch_length x load_patch_width patch (a point load when either is 0).
  double load_force = 0.04;  // N (paper: 0.041-0.044 N)
  double load_x = 0.45;      // m (paper)
  double load_y_fraction = 0.5;
  double load_patch_length = 0.01;  // m (assumption: a shaker contact pad about 1 cm across)
  double load_patch_width = 0.01;   // m
  // Output: |w| along y = output_y_fraction * width at these x positions (m, within [0, length]).
  std::vector<double> output_positions = DefaultOutputPositions();
  double output_y_fraction = 0.5;  // the top centreline

  // Checks each field against the plate of `options`; on failure `error` names the field as
  // SensorOptions' "<prefix>field".
  bool IsValid(const SensorOptions& options,
               const std::string& prefix,
               ValidationError* error) const;
};

struct SensorOptions {
  // Geometry (m).
  double length = 0.90;  // paper section 4
  double width = 0.04;   // assumption: a strip a few centimetres wide
  std::vector<Layer> layers = DefaultSensorLayers();
  // Plate theory (element.hpp): Kirchhoff (Bogner-Fox-Schmit elements), first-order shear
  // deformation with an energy-consistent shear stiffness (MITC4 elements) or the layer-wise
  // refined zigzag theory (RZT4 elements; docs/model.md, "Plate theories"). All run the same fast
  // paths. The default is RZT: near fixed clamps the soft core's shear decides the answer, and
  // against a layered 3D solid RZT is the closest (docs/model.md, "Choice of the default").
  PlateTheory theory = PlateTheory::kRzt;

  // Winkler foundation of the pipe bottom under the strip: pressure k_f (1 + i eta_f) w.
  double foundation_stiffness = 5.0e4;  // N/m^3, >= 0 (assumption)
  double foundation_loss_factor = 0.1;  // >= 0 (assumption)

  // Clamp layout: each long edge split into `clamps_per_edge` equal sections; clamp k (1-based)
  // is section k of edge A (y = 0) for k <= clamps_per_edge, else section k - clamps_per_edge of
  // edge B (y = width); sections counted from x = 0 (paper figure 2).
  int clamps_per_edge = 18;
  // A fixed clamp section clamps its edge (w = 0, normal slope = 0); this lets validation runs
  // model a simply supported fixing instead. Must not be kFree.
  Support fixed_support = Support::kClamped;
  Support short_edge_start = Support::kFree;  // edge x = 0
  Support short_edge_end = Support::kFree;    // edge x = length

  // The loads and scan lines the model answers for (one experiment each; docs/model.md, "Several
  // load cases"): at least one. Every case shares the clamps, the mesh and the frequency below,
  // so a configuration's system is factorized once and solved for every case's load; the model's
  // outputs are the cases' outputs one after the other.
  std::vector<LoadCase> load_cases = {LoadCase{}};
  double frequency_hz = 5.0;  // paper
  // The first output of case c in the concatenated outputs, and the total after the last case.
  std::size_t OutputOffset(std::size_t c) const;
  std::size_t NumOutputs() const { return OutputOffset(load_cases.size()); }

  bool normalise = true;  // divide each case's profile by its maximum, as in the paper's figures

  // Mesh: elements per clamp section along x and across the width (docs/model.md, "Convergence
  // study" and "Mesh convergence of the shear theories": with the gradings below, the default
  // meshes are within about 2 % of the peak of a 4x finer mesh in the normalised profile).
  int elements_per_section = 10;
  // Unset: the theory's own (ElementsAcrossWidth()): 6 node intervals across the width, i.e. 6
  // elements of order 1 or 3 of order 2 (the fast path's cost is set by the node lines).
  std::optional<int> elements_across_width;
  // Element order of the shear theories (plate.hpp): 1, bilinear MITC4 / RZT4 elements; 2, the
  // 9-node quadratic MITC9 / RZT9 (mitc9_element.hpp), each element spanning 2 x 2 node
  // intervals (so 3 across the width cost the fast path what 6 bilinear ones do, for a far
  // smaller discretisation error: docs/model.md, "Quadratic elements"). Kirchhoff takes only 1.
  // Unset: the theory's own (ElementOrder()): 1 for Kirchhoff (cubic BFS elements), 2 for FSDT
  // and RZT. The gradings below place the element boundaries; mid-side nodes sit at the element
  // midpoints.
  std::optional<int> element_order;
  int ElementOrder() const {
    return element_order.value_or(theory == PlateTheory::kKirchhoff ? 1 : 2);
  }
  int ElementsAcrossWidth() const { return elements_across_width.value_or(6 / ElementOrder()); }
  // Grading exponents p in [1, 3]: node t in [0, 1] of each section (along x) and of the width
  // (along y) is placed at (2t)^p / 2 for t <= 1/2 and symmetrically above, so elements shrink
  // towards the section ends and the edges, where clamped/free transitions are singular points
  // (the singularity slows the convergence of uniform meshes). 1 = uniform. Stronger grading
  // along x costs conditioning (the fast path equals the full solve to ~1e-9 at p = 3).
  double length_grading = 2.0;
  // Unset: the theory's own (WidthGrading()): 3 for Kirchhoff, whose cubic elements resolve the
  // 1 cm load patch at the centreline with the coarse middle elements; 1 (uniform) for FSDT and
  // RZT, whose bilinear elements do not (docs/model.md, "Mesh convergence of the shear theories":
  // with every clamp fixed their peak is 13 % low with p = 3 against 7 % uniform at 6 across).
  std::optional<double> width_grading;
  double WidthGrading() const {
    return width_grading.value_or(theory == PlateTheory::kKirchhoff ? 3.0 : 1.0);
  }
  // Per-configuration solver: false = unpivoted complex-symmetric block LDL^T with a pivoting-LU
  // fallback (fast; each solve's residual is checked unless fast_path_certified()); true =
  // always the dense partial-pivoting LU of the condensed system (slower; a cross-check).
  bool always_pivot = false;
  // Instruction set of the per-configuration solves (vector_kernels.hpp): the widest this CPU
  // supports by default. All give bit-identical results, so this is not part of a run's
  // fingerprint: it changes only the speed (docs/benchmarks.md).
  VectorKernels vector_kernels = VectorKernels::kAuto;

  // The precompute may use at most this much memory (bytes): options whose EstimatedMemoryBytes()
  // exceed it are invalid, so an oversized mesh is refused before anything is allocated.
  double memory_limit_bytes = kDefaultMemoryLimitBytes;

  // Peak memory (bytes) of building the model, from the mesh size (dofs per cross-section,
  // sections, elements), the distinct section and group pieces the precompute will condense, and
  // the load cases' outputs and loads (the cases share the pieces: docs/model.md, "Several load
  // cases"). Measured for Kirchhoff at 6 to 24 elements across with 1 to 4 load cases (on one
  // output line or each on its own): 1.2-1.5 x the peak RSS (less the program itself), about 2 x
  // what the finished model keeps. Not counted: the transient of the constructor's Higham
  // certificate (sparse Cholesky factorizations of the whole plate), which sets the peak of the
  // shear theories' meshes: for RZT at its default mesh the estimate is 0.4-0.65 x the peak
  // RSS (about 100 MB). Needs the sizes in range (IsValid checks them first).
  double EstimatedMemoryBytes() const;
  // Peak memory (bytes) of the continuous-unknowns precompute that a mixed run builds on its first
  // simulation (docs/model.md, "Continuous unknowns"), on top of EstimatedMemoryBytes():
  // series tables of the section pieces and output maps, the interior blocks for direct
  // condensation, and while building, the series' terms in complex form. loss_factor_unknown: the
  // unknowns include loss_factor (the tables are then real whatever the layers).
  double EstimatedContinuousMemoryBytes(bool loss_factor_unknown) const;

  // Checks every field: finite values in physical ranges (docs/config.md), sizes within the
  // kMax* limits, the estimated memory within memory_limit_bytes. On failure `error` names the
  // field ("load_x", "layers[1]::thickness", "load_cases[2].load_x", "output_positions[4]").
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "SensorOptions::field = value; constraint".
  bool IsValid(std::string* why) const;
};

// Continuous parameters a single simulation may set in place of the model's own values (unset: the
// model's value). Ranges as SensorOptions and Layer use them (docs/config.md); the stiffness scale
// is bounded so that every derived stiffness stays a finite double.
struct SensorVariation {
  // Winkler foundation stiffness k_f (N/m^3) in [0, 1e15]; the foundation keeps the model's
  // foundation_loss_factor.
  std::optional<double> foundation_stiffness;
  // s in [1e-6, 1e6]: multiplies every layer's Young's modulus, hence the laminate's bending
  // stiffness D (the neutral plane does not move; the mass does not change).
  std::optional<double> stiffness_scale;
  // eta in [0, 10]: one structural loss factor for every layer, replacing the layers' own.
  std::optional<double> loss_factor;

  bool empty() const {
    return !foundation_stiffness.has_value() && !stiffness_scale.has_value() &&
           !loss_factor.has_value();
  }
  // On failure `error` names the field (owner "SensorVariation").
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "SensorVariation::field = value; constraint".
  bool IsValid(std::string* why) const;
};

// SensorVariation's fields by name, with their ranges: the one table that IsValid, the config's
// [parameters.<name>] and the engine's simulator go through.
struct SensorVariationField {
  const char* name;
  std::optional<double> SensorVariation::*member;
  double low, high;        // closed range
  const char* range_text;  // "[0, 1e15] N/m^3", for messages
};
inline constexpr SensorVariationField kSensorVariationFields[] = {
    {"foundation_stiffness", &SensorVariation::foundation_stiffness, 0.0, 1e15, "[0, 1e15] N/m^3"},
    // A millionth to a million times the laminate: far beyond any material uncertainty, and with
    // Layer's modulus range every scaled stiffness stays a finite, non-zero double.
    {"stiffness_scale", &SensorVariation::stiffness_scale, 1e-6, 1e6, "[1e-6, 1e6]"},
    {"loss_factor", &SensorVariation::loss_factor, 0.0, 10.0, "[0, 10]"},
};
// The field called `name`, or nullptr.
const SensorVariationField* FindSensorVariationField(std::string_view name);

// `options` with the variation's values applied (youngs_modulus *= s and loss_factor = eta in
// every layer, foundation_stiffness = k_f): the model SensorModel::Profile(clamps, variation, ...)
// reproduces. The result may fail SensorOptions::IsValid (a scaled modulus out of its range).
SensorOptions ApplyVariation(SensorOptions options, const SensorVariation& variation);

// Modal analysis of one clamp configuration.
struct SensorModes {
  std::vector<double> frequencies_hz;  // undamped, ascending
  Eigen::MatrixXd shapes;              // num_outputs x count: w of each mass-normalised mode
};

// How a SensorModel builds its precomputed pieces (docs/model.md, "Start-up and the precompute
// cache"). Neither choice changes a single bit of what the model computes.
struct PrecomputeOptions {
  // Threads for the precompute's independent pieces; null: the calling thread alone.
  ThreadPool* pool = nullptr;
  // The disk cache's folder (created when missing); empty: no cache. DefaultPrecomputeCache() is
  // what the CLI and Python use.
  std::string cache_directory;
  // The cache's entries beyond this many bytes are removed, least recently used first.
  std::uint64_t cache_max_bytes = std::uint64_t{512} << 20;
};

// $COMBABC_CACHE_DIR if set (an empty value: no cache), else $XDG_CACHE_HOME/combabc/precompute,
// else $HOME/.cache/combabc/precompute; empty (no cache) when none of them is set.
std::string DefaultPrecomputeCache();

class SensorModel {
 public:
  // Throws combabc::Error if `options` is invalid.
  explicit SensorModel(const SensorOptions& options, const PrecomputeOptions& precompute = {});
  ~SensorModel();
  SensorModel(const SensorModel&) = delete;
  SensorModel& operator=(const SensorModel&) = delete;

  int num_clamps() const { return ClampPattern::Size(options_.clamps_per_edge); }
  // All load cases' outputs, case after case (SensorOptions::OutputOffset).
  int num_outputs() const { return static_cast<int>(output_positions_.size()); }
  const std::vector<double>& output_positions() const { return output_positions_; }
  int num_load_cases() const { return static_cast<int>(options_.load_cases.size()); }
  const SensorOptions& options() const { return options_; }
  const Plate& plate() const { return *plate_; }
  // Bytes held by the precomputed section pieces (the per-configuration state is on the stack).
  std::size_t PrecomputedBytes() const;
  // Whether the clamp-only fast path runs without its per-configuration residual check: the
  // dynamic stiffness with every clamp free is a Higham matrix (real and imaginary parts positive
  // definite), so every configuration's unpivoted LDL^T is provably stable (section_solve.cpp).
  // True for the default sensor; false e.g. above the first resonance.
  bool fast_path_certified() const { return fast_path_certified_; }
  // Whether the precomputed pieces came from the disk cache (PrecomputeOptions).
  bool precompute_from_cache() const { return precompute_from_cache_; }

  // clamps[k] = 1: clamp k + 1 fixed; 0: free (paper section 5). Writes |w| (m, or each case's
  // profile normalised to a maximum of 1) at the output positions of every load case. Thread-safe.
  void Profile(std::span<const std::uint8_t> clamps, std::span<double> out) const;
  // The same from a sparse LU of the whole plate (reference path).
  void ProfileFullSolve(std::span<const std::uint8_t> clamps, std::span<double> out) const;
  // n configurations, row-major (n x num_clamps in, n x num_outputs out), on `threads` threads.
  void ProfileBatch(std::span<const std::uint8_t> clamps,
                    std::size_t n,
                    std::span<double> out,
                    int threads = 1) const;

  // Complex centreline deflection (m) from the fast path, before |.| and normalisation.
  void ComplexProfile(std::span<const std::uint8_t> clamps,
                      std::span<std::complex<double>> out) const;

  // The same with continuous unknowns: the profile of ApplyVariation(options(), variation) at the
  // same mesh, without rebuilding the model. An empty variation takes the clamp-only fast path
  // above; otherwise the per-call condensation (docs/model.md, "Continuous unknowns"), whose
  // precompute is built on the first such call (one for an explicit loss factor, one for the
  // layers' own; thread-safe). Throws combabc::Error (kConfig) on an invalid variation.
  void Profile(std::span<const std::uint8_t> clamps,
               const SensorVariation& variation,
               std::span<double> out) const;
  void ComplexProfile(std::span<const std::uint8_t> clamps,
                      const SensorVariation& variation,
                      std::span<std::complex<double>> out) const;
  // n configurations with their own variations (variations.size() == n), as ProfileBatch above.
  void ProfileBatch(std::span<const std::uint8_t> clamps,
                    std::span<const SensorVariation> variations,
                    std::size_t n,
                    std::span<double> out,
                    int threads = 1) const;
  // Terms of the power series in mu (docs/model.md) each section clamp state (edge A fixed +
  // 2 x edge B fixed) sums for `variation`, or -1 where that state is condensed directly instead.
  std::array<int, 4> VariationSeriesTerms(const SensorVariation& variation) const;
  // Bytes held by the continuous-unknowns precompute built so far (0 before the first call).
  std::size_t VariationPrecomputedBytes() const;
  // The full complex field (all dofs of plate()) of a configuration under load case `load_case`,
  // by the full solve.
  Eigen::VectorXcd Field(std::span<const std::uint8_t> clamps, int load_case = 0) const;
  // Constraints of the whole plate for a configuration (used by the full solve and modes).
  Constraints ConfigurationConstraints(std::span<const std::uint8_t> clamps) const;
  // First `count` natural frequencies (real part of the stiffness, real foundation) and shapes.
  SensorModes Modes(std::span<const std::uint8_t> clamps, int count) const;

 private:
  void CheckSpans(std::span<const std::uint8_t> clamps, std::size_t out_size) const;
  void Finish(std::span<const std::complex<double>> w, std::span<double> out) const;
  // The layout's inputs: every case's load vector (a column each) and outputs.
  Eigen::MatrixXd LoadMatrix() const;
  std::vector<CaseOutputs> CaseOutputList() const;
  // The precompute for `variation` (built on first use) and the factors mapping the variation's
  // dynamic stiffness onto it: K(theta) = factor (K_base + mu M_1).
  const ContinuousCondensation& Continuous(const SensorVariation& variation,
                                           std::complex<double>* factor,
                                           std::complex<double>* mu) const;

  SensorOptions options_;
  std::vector<double> output_positions_;  // every case's, concatenated
  std::unique_ptr<Plate> plate_;
  // The sections, their free dofs, outputs and loads: every condensation's (shared with them).
  std::shared_ptr<const SectionLayout> layout_;
  std::unique_ptr<SectionCondensation> condensation_;  // every load case
  bool fast_path_certified_ = false;
  bool precompute_from_cache_ = false;
  std::unique_ptr<ContinuousCache> continuous_;
};

}  // namespace combabc::plate
