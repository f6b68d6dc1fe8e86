#include "combabc/plate/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>

#include "combabc/core/error.hpp"
#include "combabc/core/thread_pool.hpp"
#include "plate/fast_path/continuous_condensation.hpp"
#include "plate/fast_path/higham_check.hpp"
#include "plate/fast_path/precompute_cache.hpp"
#include "plate/fast_path/section_condensation.hpp"
#include "plate/fast_path/section_layout.hpp"

namespace combabc::plate {
namespace {

// Graded position of node k of n in [0, 1] (SensorOptions::length_grading).
double Graded(int k, int n, double grading) {
  const double t = static_cast<double>(k) / n;
  return t <= 0.5 ? 0.5 * std::pow(2.0 * t, grading) : 1.0 - 0.5 * std::pow(2.0 - 2.0 * t, grading);
}

// Node lines on every section boundary, `elements_per_section` elements in each section; at
// element order 2 a node line at each element's midpoint too.
Grid SensorGrid(const SensorOptions& o) {
  Grid grid;
  const double section = o.length / o.clamps_per_edge;
  const int m = o.elements_per_section;
  for (int s = 0; s < o.clamps_per_edge; ++s) {
    for (int e = 0; e < m; ++e) {
      const double x0 = section * (s + Graded(e, m, o.length_grading));
      grid.x.push_back(x0);
      if (o.ElementOrder() == 2) {
        const double x1 = section * (s + Graded(e + 1, m, o.length_grading));
        grid.x.push_back(0.5 * (x0 + x1));
      }
    }
  }
  grid.x.push_back(o.length);
  const int n = o.ElementsAcrossWidth();
  for (int j = 0; j <= n; ++j) {
    const double y0 = o.width * Graded(j, n, o.WidthGrading());
    grid.y.push_back(y0);
    if (o.ElementOrder() == 2 && j < n) {
      grid.y.push_back(0.5 * (y0 + o.width * Graded(j + 1, n, o.WidthGrading())));
    }
  }
  grid.y.back() = o.width;
  return grid;
}

Load SensorLoad(const SensorOptions& o, const LoadCase& c) {
  Load load;
  load.x = c.load_x;
  load.y = c.load_y_fraction * o.width;
  load.force = c.load_force;
  if (c.load_patch_length > 0.0 && c.load_patch_width > 0.0) {
    load.patch_length = c.load_patch_length;
    load.patch_width = c.load_patch_width;
  }
  return load;
}

// Everything the condensation depends on (precompute_cache.hpp): the build of this code, the
// mesh and its element matrices (which carry the laminate, the theory and the foundation), the
// supports, the loads, the outputs and the frequency.
PrecomputeKey KeyOf(const Plate& plate,
                    const SensorOptions& o,
                    int group_size,
                    const SectionLayout& layout) {
  KeyHasher h;
  h.AddText(PlateBuildId());
  h.AddValue(static_cast<int>(plate.theory()));
  for (int v : {plate.element_order(),
                plate.dofs_per_node(),
                plate.element_dofs(),
                plate.num_elements_x(),
                plate.num_elements_y()}) {
    h.AddValue(v);
  }
  h.AddValue(plate.grid().x.size());
  h.Add(plate.grid().x.data(), sizeof(double) * plate.grid().x.size());
  h.AddValue(plate.grid().y.size());
  h.Add(plate.grid().y.data(), sizeof(double) * plate.grid().y.size());
  // Elements of equal size share their matrices: each distinct one once, then which is where.
  std::vector<const ElementMatrices*> distinct;
  for (int ex = 0; ex < plate.num_elements_x(); ++ex) {
    for (int ey = 0; ey < plate.num_elements_y(); ++ey) {
      const ElementMatrices* e = &plate.Element(ex, ey);
      auto it = std::find(distinct.begin(), distinct.end(), e);
      if (it == distinct.end()) {
        h.AddMatrix(e->stiffness_real);
        h.AddMatrix(e->stiffness_imag);
        h.AddMatrix(e->mass_unit);
        h.AddMatrix(e->rotary_inertia);
        it = distinct.insert(distinct.end(), e);
      }
      h.AddValue(it - distinct.begin());
    }
  }
  h.AddValue(plate.foundation_stiffness());
  h.AddValue(plate.foundation_loss_factor());
  h.AddValue(plate.MassCoefficient(o.frequency_hz));
  h.AddValue(o.frequency_hz);
  h.AddValue(o.clamps_per_edge);
  h.AddValue(o.elements_per_section);
  h.AddValue(group_size);
  h.AddValue(layout.masks());
  h.AddValue(o.always_pivot);
  h.AddMatrix(layout.loads());
  h.AddValue(layout.outputs().size());
  for (const CaseOutputs& c : layout.outputs()) {
    h.AddValue(c.y);
    h.AddValue(c.x.size());
    h.Add(c.x.data(), sizeof(double) * c.x.size());
  }
  return h.Finish();
}

// The largest cache payload this model's pieces can take: what the precompute keeps is part of
// its estimated peak (SensorOptions::EstimatedMemoryBytes), so twice the estimate and a MiB of
// headers is far above any true entry and far below what a planted file could make us allocate.
std::uint64_t MaxPrecomputeBytes(const SensorOptions& o) {
  return static_cast<std::uint64_t>(2.0 * o.EstimatedMemoryBytes()) + (std::uint64_t{1} << 20);
}

}  // namespace

std::string DefaultPrecomputeCache() {
  if (const char* dir = std::getenv("COMBABC_CACHE_DIR")) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg == '/') {
    return std::string(xdg) + "/combabc/precompute";
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    return std::string(home) + "/.cache/combabc/precompute";
  }
  return "";
}

SensorModel::SensorModel(const SensorOptions& options, const PrecomputeOptions& precompute)
    : options_(options) {
  ValidationError error;
  if (!options_.IsValid(&error)) {
    throw Error(ErrorKind::kConfig, error.Message(), "", 0, error.owner + "::" + error.field);
  }
  plate_ = std::make_unique<Plate>(SensorGrid(options_),
                                   EquivalentSingleLayer(options_.layers),
                                   options_.foundation_stiffness,
                                   options_.foundation_loss_factor,
                                   options_.theory,
                                   options_.ElementOrder());
  for (const LoadCase& c : options_.load_cases) {
    output_positions_.insert(
        output_positions_.end(), c.output_positions.begin(), c.output_positions.end());
  }
  const CrossSectionMasks masks{
      SupportMask(Edge::kBottom, options_.fixed_support, options_.theory),
      SupportMask(Edge::kTop, options_.fixed_support, options_.theory),
      SupportMask(Edge::kLeft, options_.short_edge_start, options_.theory),
      SupportMask(Edge::kRight, options_.short_edge_end, options_.theory)};
  // Every load case shares the clamps, the mesh and the frequency: one layout and one
  // condensation take them all, and each configuration is factorized once for every case's load
  // (docs/model.md, "Several load cases").
  layout_ = std::make_shared<const SectionLayout>(*plate_,
                                                  options_.clamps_per_edge,
                                                  options_.elements_per_section,
                                                  masks,
                                                  LoadMatrix(),
                                                  CaseOutputList());
  // Groups of 3 sections (64 states each) when the layout allows: 18 sections -> 5 unknown
  // cross-sections per configuration, ~14 MiB of pieces (docs/model.md).
  const int group_size =
      options_.clamps_per_edge % 3 == 0 ? 3 : (options_.clamps_per_edge % 2 == 0 ? 2 : 1);
  const VectorKernels kernels = ResolveKernels(options_.vector_kernels);
  const PrecomputeCache cache(precompute.cache_directory, precompute.cache_max_bytes);
  PrecomputeKey key{};
  if (!precompute.cache_directory.empty()) {
    key = KeyOf(*plate_, options_, group_size, *layout_);
    std::unique_ptr<SectionCondensation> read;
    if (cache.Load(key, MaxPrecomputeBytes(options_), [&](ByteReader& reader) {
          read = SectionCondensation::Read(reader, layout_, kernels);
          return read != nullptr;
        })) {
      condensation_ = std::move(read);
      precompute_from_cache_ = true;
    }
  }
  if (condensation_ == nullptr) {
    SectionCondensation::Settings settings;
    settings.group_size = group_size;
    settings.frequency_hz = options_.frequency_hz;
    settings.always_pivot = options_.always_pivot;
    settings.higham = IsHighamSystem(*plate_, *layout_, options_.frequency_hz);
    settings.kernels = kernels;
    settings.pool = precompute.pool;
    condensation_ = std::make_unique<SectionCondensation>(*plate_, layout_, settings);
    if (!precompute.cache_directory.empty()) {
      cache.Store(key, [&](ByteWriter& writer) { condensation_->Write(writer); });
    }
  }
  fast_path_certified_ = condensation_->higham();
  continuous_ = std::make_unique<ContinuousCache>();
  // Proportional damping, K_imag = eta K_real: the layers' own loss factors then need no
  // precompute of their own. It holds when every layer has one loss factor, and also when every
  // layer has one Poisson ratio (each layer's bending matrix then has the same shape), as in the
  // default laminate (eta = 0.10 from 0.10 / 0.15 / 0.10).
  const PlateSection& section = plate_->section();
  const double eta = section.bending_imag(0, 0) / section.bending_real(0, 0);
  // In FSDT the shear stiffness must carry the same eta (it does not for the default laminate:
  // the shear follows the core's loss factor), in RZT every zigzag stiffness.
  auto proportional = [eta](const auto& imag, const auto& real) {
    return (imag - eta * real).cwiseAbs().maxCoeff() <= 1e-14 * real.cwiseAbs().maxCoeff();
  };
  bool theory_proportional = true;
  switch (options_.theory) {
    case PlateTheory::kKirchhoff:
      break;
    case PlateTheory::kFsdt:
      theory_proportional =
          std::abs(section.shear_imag - eta * section.shear_real) <= 1e-14 * section.shear_real;
      break;
    case PlateTheory::kRzt:
      theory_proportional =
          proportional(section.zigzag_bending_imag, section.zigzag_bending_real) &&
          proportional(section.zigzag_shear_imag, section.zigzag_shear_real);
      break;
  }
  continuous_->proportional =
      proportional(section.bending_imag, section.bending_real) && theory_proportional;
  continuous_->own_loss_factor = eta;
}

SensorModel::~SensorModel() = default;

Eigen::MatrixXd SensorModel::LoadMatrix() const {
  Eigen::MatrixXd loads(plate_->num_dofs(), num_load_cases());
  for (int c = 0; c < num_load_cases(); ++c) {
    loads.col(c) = plate_->LoadVector(SensorLoad(options_, options_.load_cases[c]));
  }
  return loads;
}

std::vector<CaseOutputs> SensorModel::CaseOutputList() const {
  std::vector<CaseOutputs> outputs;
  for (const LoadCase& c : options_.load_cases) {
    outputs.push_back({c.output_positions, c.output_y_fraction * options_.width});
  }
  return outputs;
}

std::size_t SensorModel::PrecomputedBytes() const { return condensation_->MemoryBytes(); }

const ContinuousCondensation& SensorModel::Continuous(const SensorVariation& variation,
                                                      std::complex<double>* factor,
                                                      std::complex<double>* mu) const {
  // K(theta) = s (K_real + i K_imag') + k_f (1 + i eta_f) M_1 - omega^2 rho h M_1, where K_imag'
  // is eta K_real for a given loss factor, else the layers' own K_imag. Factoring out what
  // multiplies the bending stiffness leaves one complex number mu on M_1
  // (continuous_condensation.hpp).
  const double s = variation.stiffness_scale.value_or(1.0);
  const bool own = !variation.loss_factor.has_value() && !continuous_->proportional;
  const double eta = variation.loss_factor.value_or(continuous_->own_loss_factor);
  *factor = own ? std::complex<double>(s, 0.0) : std::complex<double>(s, s * eta);
  const double k_f = variation.foundation_stiffness.value_or(options_.foundation_stiffness);
  const double omega = 2.0 * M_PI * options_.frequency_hz;
  const std::complex<double> b(k_f - omega * omega * plate_->section().mass_per_area,
                               k_f * options_.foundation_loss_factor);
  *mu = b / *factor;
  const int index = own ? 1 : 0;
  std::call_once(continuous_->once[index], [&] {
    ContinuousCondensation::Settings settings;
    settings.own_loss_factors = own;
    settings.always_pivot = options_.always_pivot;
    settings.kernels = ResolveKernels(options_.vector_kernels);
    continuous_->base[index] = std::make_unique<ContinuousCondensation>(*plate_, layout_, settings);
    continuous_->ready[index].store(continuous_->base[index].get(), std::memory_order_release);
  });
  return *continuous_->base[index];
}

void SensorModel::CheckSpans(std::span<const std::uint8_t> clamps, std::size_t out_size) const {
  if (clamps.size() != static_cast<std::size_t>(num_clamps())) {
    throw Error(ErrorKind::kConfig,
                "clamps must have num_clamps() = " + std::to_string(num_clamps()) + " entries",
                "",
                0,
                "clamps");
  }
  if (out_size != static_cast<std::size_t>(num_outputs())) {
    throw Error(ErrorKind::kConfig,
                "out must have num_outputs() = " + std::to_string(num_outputs()) + " entries",
                "",
                0,
                "out");
  }
}

void SensorModel::Finish(std::span<const std::complex<double>> w, std::span<double> out) const {
  for (std::size_t c = 0; c < options_.load_cases.size(); ++c) {
    const std::size_t begin = options_.OutputOffset(c);
    const std::size_t end = options_.OutputOffset(c + 1);
    double peak = 0.0;
    for (std::size_t k = begin; k < end; ++k) {
      out[k] = std::abs(w[k]);
      peak = std::max(peak, out[k]);
    }
    if (options_.normalise && peak > 0.0) {
      for (std::size_t k = begin; k < end; ++k) out[k] /= peak;
    }
  }
}

void SensorModel::ComplexProfile(std::span<const std::uint8_t> clamps,
                                 std::span<std::complex<double>> out) const {
  CheckSpans(clamps, out.size());
  condensation_->Solve(clamps, out);
}

void SensorModel::Profile(std::span<const std::uint8_t> clamps, std::span<double> out) const {
  CheckSpans(clamps, out.size());
  // Reused per thread: no allocation per configuration.
  thread_local std::vector<std::complex<double>> w;
  w.resize(out.size());
  ComplexProfile(clamps, w);
  Finish(w, out);
}

Constraints SensorModel::ConfigurationConstraints(std::span<const std::uint8_t> clamps) const {
  const int n = options_.clamps_per_edge;
  const ClampPattern pattern(clamps, n);
  Constraints c = plate_->NewConstraints();
  const std::vector<double>& x = plate_->grid().x;
  // Grid intervals per section (2 per element at element order 2).
  const auto m = static_cast<std::size_t>(options_.ElementOrder()) *
                 static_cast<std::size_t>(options_.elements_per_section);
  for (int s = 0; s < n; ++s) {
    // Closed intervals: the node shared with a free neighbour is fixed too (docs/model.md).
    const double start = x[static_cast<std::size_t>(s) * m];
    const double end = x[static_cast<std::size_t>(s + 1) * m];
    if (pattern.Fixed(ClampPattern::kEdgeA, s)) {
      c.AddEdgeSupport(Edge::kBottom, start, end, options_.fixed_support);
    }
    if (pattern.Fixed(ClampPattern::kEdgeB, s)) {
      c.AddEdgeSupport(Edge::kTop, start, end, options_.fixed_support);
    }
  }
  c.AddEdgeSupport(Edge::kLeft, options_.short_edge_start);
  c.AddEdgeSupport(Edge::kRight, options_.short_edge_end);
  return c;
}

Eigen::VectorXcd SensorModel::Field(std::span<const std::uint8_t> clamps, int load_case) const {
  CheckSpans(clamps, static_cast<std::size_t>(num_outputs()));
  if (load_case < 0 || load_case >= num_load_cases()) {
    throw Error(ErrorKind::kConfig,
                "load_case must be in [0, " + std::to_string(num_load_cases()) + ")",
                "",
                0,
                "load_case");
  }
  return plate_->SolveHarmonic(ConfigurationConstraints(clamps),
                               SensorLoad(options_, options_.load_cases[load_case]),
                               options_.frequency_hz);
}

void SensorModel::ProfileFullSolve(std::span<const std::uint8_t> clamps,
                                   std::span<double> out) const {
  CheckSpans(clamps, out.size());
  std::vector<std::complex<double>> w(out.size());
  for (int c = 0; c < num_load_cases(); ++c) {
    const Eigen::VectorXcd u = Field(clamps, c);
    const LoadCase& lc = options_.load_cases[c];
    const double y = lc.output_y_fraction * options_.width;
    for (std::size_t k = 0; k < lc.output_positions.size(); ++k) {
      w[options_.OutputOffset(c) + k] = plate_->Deflection(u, lc.output_positions[k], y);
    }
  }
  Finish(w, out);
}

void SensorModel::ProfileBatch(std::span<const std::uint8_t> clamps,
                               std::size_t n,
                               std::span<double> out,
                               int threads) const {
  const std::size_t nk = static_cast<std::size_t>(num_clamps());
  const std::size_t no = static_cast<std::size_t>(num_outputs());
  if (clamps.size() != n * nk || out.size() != n * no) {
    throw Error(ErrorKind::kConfig,
                "ProfileBatch: clamps must be n x num_clamps and out n x num_outputs",
                "",
                0,
                "clamps");
  }
  if (threads < 0) throw Error(ErrorKind::kConfig, "threads must be >= 0", "", 0, "threads");
  // Each configuration writes only its own row, so the result does not depend on the schedule.
  ThreadPool pool(threads);
  pool.ParallelFor(n, 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Profile(clamps.subspan(i * nk, nk), out.subspan(i * no, no));
    }
  });
}

SensorModes SensorModel::Modes(std::span<const std::uint8_t> clamps, int count) const {
  CheckSpans(clamps, static_cast<std::size_t>(num_outputs()));
  const plate::Modes modes = plate_->ComputeModes(ConfigurationConstraints(clamps), count);
  SensorModes result;
  result.frequencies_hz = modes.frequencies_hz;
  result.shapes.resize(num_outputs(), count);
  for (int c = 0; c < count; ++c) {
    const Eigen::VectorXd shape = modes.shapes.col(c);
    for (const LoadCase& lc : options_.load_cases) {
      const double y = lc.output_y_fraction * options_.width;
      const auto offset = static_cast<int>(options_.OutputOffset(&lc - options_.load_cases.data()));
      for (std::size_t k = 0; k < lc.output_positions.size(); ++k) {
        result.shapes(offset + static_cast<int>(k), c) =
            plate_->Deflection(shape, lc.output_positions[k], y);
      }
    }
  }
  return result;
}

}  // namespace combabc::plate
