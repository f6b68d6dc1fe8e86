#include <cmath>
#include <sstream>

#include "combabc/plate/sensor_model.hpp"

namespace combabc::plate {
namespace {

template <typename T>
bool Fail(std::string* why, const char* field, T value, const char* constraint) {
  if (why != nullptr) {
    std::ostringstream os;
    os << "SensorOptions::" << field << " = " << value << "; " << constraint;
    *why = os.str();
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

bool SensorOptions::IsValid(std::string* why) const {
  if (!(length > 0.0)) return Fail(why, "length", length, "must be > 0");
  if (!(width > 0.0)) return Fail(why, "width", width, "must be > 0");
  if (layers.empty()) return Fail(why, "layers.size()", 0, "must be >= 1");
  for (std::size_t k = 0; k < layers.size(); ++k) {
    if (!layers[k].IsValid(why, "SensorOptions::layers[" + std::to_string(k) + "]")) return false;
  }
  if (!(foundation_stiffness >= 0.0)) {
    return Fail(why, "foundation_stiffness", foundation_stiffness, "must be >= 0");
  }
  if (!(foundation_loss_factor >= 0.0)) {
    return Fail(why, "foundation_loss_factor", foundation_loss_factor, "must be >= 0");
  }
  if (clamps_per_edge < 1) return Fail(why, "clamps_per_edge", clamps_per_edge, "must be >= 1");
  if (fixed_support == Support::kFree) {
    return Fail(why, "fixed_support", ToString(fixed_support), "must not be free");
  }
  if (!std::isfinite(load_force)) return Fail(why, "load_force", load_force, "must be finite");
  if (!(load_x >= 0.0 && load_x <= length)) {
    return Fail(why, "load_x", load_x, "must be in [0, length]");
  }
  if (!(load_y_fraction >= 0.0 && load_y_fraction <= 1.0)) {
    return Fail(why, "load_y_fraction", load_y_fraction, "must be in [0, 1]");
  }
  if (!(load_patch_length >= 0.0)) {
    return Fail(why, "load_patch_length", load_patch_length, "must be >= 0");
  }
  if (!(load_patch_width >= 0.0)) {
    return Fail(why, "load_patch_width", load_patch_width, "must be >= 0");
  }
  if (!(frequency_hz >= 0.0 && std::isfinite(frequency_hz))) {
    return Fail(why, "frequency_hz", frequency_hz, "must be finite and >= 0");
  }
  if (output_positions.empty()) return Fail(why, "output_positions.size()", 0, "must be >= 1");
  for (std::size_t k = 0; k < output_positions.size(); ++k) {
    if (!(output_positions[k] >= 0.0 && output_positions[k] <= length)) {
      const std::string field = "output_positions[" + std::to_string(k) + "]";
      return Fail(why, field.c_str(), output_positions[k], "must be in [0, length]");
    }
  }
  if (!(output_y_fraction >= 0.0 && output_y_fraction <= 1.0)) {
    return Fail(why, "output_y_fraction", output_y_fraction, "must be in [0, 1]");
  }
  if (elements_per_section < 1) {
    return Fail(why, "elements_per_section", elements_per_section, "must be >= 1");
  }
  if (elements_across_width < 1) {
    return Fail(why, "elements_across_width", elements_across_width, "must be >= 1");
  }
  if (!(length_grading >= 1.0 && length_grading <= 3.0)) {
    return Fail(why, "length_grading", length_grading, "must be in [1, 3]");
  }
  if (!(width_grading >= 1.0 && width_grading <= 3.0)) {
    return Fail(why, "width_grading", width_grading, "must be in [1, 3]");
  }
  return true;
}

}  // namespace combabc::plate
