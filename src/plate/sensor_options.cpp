#include <cmath>
#include <sstream>

#include "combabc/plate/sensor_model.hpp"

namespace combabc::plate {
namespace {

template <typename T>
bool Fail(ValidationError* error,
          const std::string& field,
          T value,
          const std::string& constraint) {
  if (error != nullptr) {
    std::ostringstream os;
    os << value;
    *error = {"SensorOptions", field, os.str(), constraint};
  }
  return false;
}

}  // namespace

std::vector<Layer> DefaultSensorLayers() {
  // Assumptions (docs/model.md, "Defaults"): thicknesses, moduli, densities and loss factors of
  // common polyurethane / silicone elastomers.
  Layer base;
  base.thickness = 1.5e-3;
  base.youngs_modulus = 30.0e6;
  base.poisson_ratio = 0.45;
  base.density = 1150.0;
  base.loss_factor = 0.10;
  Layer core;
  core.thickness = 1.0e-3;
  core.youngs_modulus = 5.0e6;
  core.poisson_ratio = 0.45;
  core.density = 1100.0;
  core.loss_factor = 0.15;
  Layer cover = base;
  return {base, core, cover};
}

std::vector<double> DefaultOutputPositions() {
  std::vector<double> x;
  for (int k = 0; k <= 90; ++k) x.push_back(0.01 * k);
  return x;
}

namespace {

// "about 7.2 GB": memory for messages, in 10^9 bytes.
std::string Gigabytes(double bytes) {
  std::ostringstream os;
  os.precision(bytes < 1e8 ? 2 : 3);
  os << bytes / 1e9 << " GB";
  return os.str();
}

bool InRange(double value, double lo, double hi) { return value >= lo && value <= hi; }

// The size whose default would save the most of the `needed` bytes, so that the message names
// what to lower; with every size at or below its default, the limit itself is what to change.
const char* MemoryCulprit(const SensorOptions& options, double needed) {
  const SensorOptions defaults;
  const char* culprit = "memory_limit_bytes";
  double best = needed;
  auto consider = [&](const char* field, const SensorOptions& smaller) {
    const double bytes = smaller.EstimatedMemoryBytes();
    if (bytes < best) {
      best = bytes;
      culprit = field;
    }
  };
  SensorOptions o = options;
  // The default of this model's theory and order (6 node intervals across).
  o.elements_across_width = std::min(options.ElementsAcrossWidth(), 6 / options.ElementOrder());
  consider("elements_across_width", o);
  o = options;
  o.elements_per_section = std::min(options.elements_per_section, defaults.elements_per_section);
  consider("elements_per_section", o);
  o = options;
  o.clamps_per_edge = std::min(options.clamps_per_edge, defaults.clamps_per_edge);
  consider("clamps_per_edge", o);
  o = options;
  for (LoadCase& c : o.load_cases) {
    c.output_positions.resize(std::min<std::size_t>(c.output_positions.size(), 101));
  }
  consider("output_positions.size()", o);
  return culprit;
}

}  // namespace

bool LoadCase::IsValid(const SensorOptions& o,
                       const std::string& prefix,
                       ValidationError* error) const {
  const double length = o.length;
  const double width = o.width;
  auto field = [&prefix](const std::string& name) { return prefix + name; };
  if (!InRange(load_force, -1e6, 1e6)) {
    return Fail(error, field("load_force"), load_force, "must be in [-1e6, 1e6] N");
  }
  std::ostringstream plate_range;
  plate_range << "must lie on the plate, in [0, " << length << "] m";
  const std::string on_plate = plate_range.str();
  if (!InRange(load_x, 0.0, length)) return Fail(error, field("load_x"), load_x, on_plate);
  if (!InRange(load_y_fraction, 0.0, 1.0)) {
    return Fail(error, field("load_y_fraction"), load_y_fraction, "must be in [0, 1]");
  }
  // A patch is 0 (a point load) or at least a nanometre: thinner patches round to zero width at
  // the load position and the patch integral breaks down.
  auto patch_ok = [](double size, double most) { return size == 0.0 || InRange(size, 1e-9, most); };
  if (!patch_ok(load_patch_length, length)) {
    return Fail(error,
                field("load_patch_length"),
                load_patch_length,
                "must be 0 or in [1e-9, the plate's length] m");
  }
  if (!patch_ok(load_patch_width, width)) {
    return Fail(error,
                field("load_patch_width"),
                load_patch_width,
                "must be 0 or in [1e-9, the plate's width] m");
  }
  if (output_positions.empty() || output_positions.size() > kMaxOutputPositions) {
    return Fail(error,
                field("output_positions.size()"),
                output_positions.size(),
                "must be in [1, " + std::to_string(kMaxOutputPositions) + "]");
  }
  for (std::size_t k = 0; k < output_positions.size(); ++k) {
    if (!InRange(output_positions[k], 0.0, length)) {
      const std::string name = field("output_positions[" + std::to_string(k) + "]");
      return Fail(error, name, output_positions[k], on_plate);
    }
  }
  if (!InRange(output_y_fraction, 0.0, 1.0)) {
    return Fail(error, field("output_y_fraction"), output_y_fraction, "must be in [0, 1]");
  }
  return true;
}

std::size_t SensorOptions::OutputOffset(std::size_t c) const {
  std::size_t offset = 0;
  for (std::size_t k = 0; k < c && k < load_cases.size(); ++k) {
    offset += load_cases[k].output_positions.size();
  }
  return offset;
}

bool SensorOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool SensorOptions::IsValid(ValidationError* error) const {
  // Physical ranges (docs/config.md, "[model]"): generous for any strip sensor, tight enough that
  // every derived quantity (stiffness, mass, omega^2, element sizes) stays a finite double.
  if (!InRange(length, 1e-3, 1e3)) return Fail(error, "length", length, "must be in [1e-3, 1e3] m");
  if (!InRange(width, 1e-4, 1e2)) return Fail(error, "width", width, "must be in [1e-4, 1e2] m");
  if (layers.empty() || layers.size() > 100) {
    return Fail(error, "layers.size()", layers.size(), "must be in [1, 100]");
  }
  for (std::size_t k = 0; k < layers.size(); ++k) {
    if (!layers[k].IsValid(error)) {
      if (error != nullptr) {
        error->owner = "SensorOptions";
        error->field = "layers[" + std::to_string(k) + "]::" + error->field;
      }
      return false;
    }
  }
  if (!InRange(foundation_stiffness, 0.0, 1e15)) {
    return Fail(error, "foundation_stiffness", foundation_stiffness, "must be in [0, 1e15] N/m^3");
  }
  if (!InRange(foundation_loss_factor, 0.0, 10.0)) {
    return Fail(error, "foundation_loss_factor", foundation_loss_factor, "must be in [0, 10]");
  }
  if (clamps_per_edge < 1 || clamps_per_edge > kMaxClampsPerEdge) {
    return Fail(error,
                "clamps_per_edge",
                clamps_per_edge,
                "must be in [1, " + std::to_string(kMaxClampsPerEdge) + "]");
  }
  if (fixed_support == Support::kFree) {
    return Fail(error, "fixed_support", ToString(fixed_support), "must not be free");
  }
  if (std::string_view(ToString(theory)) == "?") {
    return Fail(error, "theory", static_cast<int>(theory), "must be kirchhoff, fsdt or rzt");
  }
  if (!InRange(frequency_hz, 0.0, 1e6)) {
    return Fail(error, "frequency_hz", frequency_hz, "must be in [0, 1e6] Hz");
  }
  if (load_cases.empty() || load_cases.size() > kMaxLoadCases) {
    return Fail(error,
                "load_cases.size()",
                load_cases.size(),
                "must be in [1, " + std::to_string(kMaxLoadCases) + "]");
  }
  for (std::size_t c = 0; c < load_cases.size(); ++c) {
    // One case keeps the field names it had before there were several ("load_x").
    const std::string prefix =
        load_cases.size() == 1 ? "" : "load_cases[" + std::to_string(c) + "].";
    if (!load_cases[c].IsValid(*this, prefix, error)) return false;
  }
  std::size_t outputs = 0;
  for (const LoadCase& c : load_cases) outputs += c.output_positions.size();
  if (outputs > kMaxOutputPositions) {
    return Fail(error,
                "load_cases[*].output_positions.size()",
                outputs,
                "must add up to at most " + std::to_string(kMaxOutputPositions));
  }
  if (elements_per_section < 1 || elements_per_section > kMaxElementsPerSection) {
    return Fail(error,
                "elements_per_section",
                elements_per_section,
                "must be in [1, " + std::to_string(kMaxElementsPerSection) + "]");
  }
  if (ElementsAcrossWidth() < 1 || ElementsAcrossWidth() > kMaxElementsAcrossWidth) {
    return Fail(error,
                "elements_across_width",
                ElementsAcrossWidth(),
                "must be in [1, " + std::to_string(kMaxElementsAcrossWidth) + "]");
  }
  if (ElementOrder() != 1 && ElementOrder() != 2) {
    return Fail(error, "element_order", ElementOrder(), "must be 1 or 2");
  }
  if (ElementOrder() == 2 && theory == PlateTheory::kKirchhoff) {
    return Fail(error,
                "element_order",
                ElementOrder(),
                "must be 1 with theory kirchhoff (its elements are cubic already; 2 is for fsdt "
                "and rzt)");
  }
  if (!InRange(length_grading, 1.0, 3.0)) {
    return Fail(error, "length_grading", length_grading, "must be in [1, 3]");
  }
  if (!InRange(WidthGrading(), 1.0, 3.0)) {
    return Fail(error, "width_grading", WidthGrading(), "must be in [1, 3]");
  }
  if (!CpuSupports(vector_kernels)) {
    return Fail(error,
                "vector_kernels",
                vector_kernels == VectorKernels::kAvx2 ? "avx2" : "avx512",
                "this CPU does not support that instruction set (kAuto picks the widest it has)");
  }
  if (!(memory_limit_bytes > 0.0) || !std::isfinite(memory_limit_bytes)) {
    return Fail(error, "memory_limit_bytes", memory_limit_bytes, "must be finite and > 0");
  }
  const double needed = EstimatedMemoryBytes();
  if (needed > memory_limit_bytes) {
    const std::string field = MemoryCulprit(*this, needed);
    double value = static_cast<double>(NumOutputs());
    if (field == "elements_across_width") value = ElementsAcrossWidth();
    if (field == "elements_per_section") value = elements_per_section;
    if (field == "clamps_per_edge") value = clamps_per_edge;
    if (field == "memory_limit_bytes") value = memory_limit_bytes;
    const std::string message = "the model would need about " + Gigabytes(needed) +
                                " of memory (limit " + Gigabytes(memory_limit_bytes) + ")";
    return Fail(error, field, value, message);
  }
  return true;
}

}  // namespace combabc::plate
