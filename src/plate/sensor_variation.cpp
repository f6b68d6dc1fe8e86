// SensorModel with continuous unknowns (docs/model.md, "Continuous unknowns"): validation of a
// SensorVariation, the options it stands for, and the per-call entry points over
// ContinuousCondensation.
#include <sstream>

#include "combabc/core/error.hpp"
#include "combabc/core/thread_pool.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "plate/fast_path/continuous_condensation.hpp"

namespace combabc::plate {
namespace {

bool FailVariation(ValidationError* error,
                   const char* field,
                   double value,
                   const std::string& constraint) {
  if (error != nullptr) {
    std::ostringstream os;
    os << value;
    *error = {"SensorVariation", field, os.str(), constraint};
  }
  return false;
}

// The error a simulation with an invalid variation throws: the sentence, at the field.
[[noreturn]] void ThrowInvalid(const ValidationError& error) {
  throw Error(ErrorKind::kConfig, error.Message(), "", 0, error.owner + "::" + error.field);
}

bool Within(double value, double lo, double hi) { return value >= lo && value <= hi; }

}  // namespace

bool SensorVariation::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool SensorVariation::IsValid(ValidationError* error) const {
  // The ranges of SensorOptions::foundation_stiffness and Layer::loss_factor (docs/config.md);
  // NaN fails every comparison.
  for (const SensorVariationField& field : kSensorVariationFields) {
    const std::optional<double>& value = this->*field.member;
    if (value && !Within(*value, field.low, field.high)) {
      return FailVariation(
          error, field.name, *value, std::string("must be in ") + field.range_text);
    }
  }
  return true;
}

const SensorVariationField* FindSensorVariationField(std::string_view name) {
  for (const SensorVariationField& field : kSensorVariationFields) {
    if (name == field.name) return &field;
  }
  return nullptr;
}

SensorOptions ApplyVariation(SensorOptions options, const SensorVariation& variation) {
  if (variation.foundation_stiffness) {
    options.foundation_stiffness = *variation.foundation_stiffness;
  }
  for (Layer& layer : options.layers) {
    if (variation.stiffness_scale) layer.youngs_modulus *= *variation.stiffness_scale;
    if (variation.loss_factor) layer.loss_factor = *variation.loss_factor;
  }
  return options;
}

void SensorModel::ComplexProfile(std::span<const std::uint8_t> clamps,
                                 const SensorVariation& variation,
                                 std::span<std::complex<double>> out) const {
  if (variation.empty()) {
    ComplexProfile(clamps, out);  // the clamp-only fast path
    return;
  }
  CheckSpans(clamps, out.size());
  ValidationError error;
  if (!variation.IsValid(&error)) ThrowInvalid(error);
  std::complex<double> factor;
  std::complex<double> mu;
  const ContinuousCondensation& continuous = Continuous(variation, &factor, &mu);
  continuous.Solve(clamps, mu, out);
  // The solve was of K / factor.
  const std::complex<double> inverse = 1.0 / factor;
  for (std::complex<double>& v : out) v *= inverse;
}

void SensorModel::Profile(std::span<const std::uint8_t> clamps,
                          const SensorVariation& variation,
                          std::span<double> out) const {
  CheckSpans(clamps, out.size());
  // Reused per thread: no allocation per configuration.
  thread_local std::vector<std::complex<double>> w;
  w.resize(out.size());
  ComplexProfile(clamps, variation, w);
  Finish(w, out);
}

void SensorModel::ProfileBatch(std::span<const std::uint8_t> clamps,
                               std::span<const SensorVariation> variations,
                               std::size_t n,
                               std::span<double> out,
                               int threads) const {
  const std::size_t nk = static_cast<std::size_t>(num_clamps());
  const std::size_t no = static_cast<std::size_t>(num_outputs());
  if (clamps.size() != n * nk || out.size() != n * no || variations.size() != n) {
    throw Error(ErrorKind::kConfig,
                "ProfileBatch: clamps must be n x num_clamps, variations n and out n x num_outputs",
                "",
                0,
                "clamps");
  }
  if (threads < 0) throw Error(ErrorKind::kConfig, "threads must be >= 0", "", 0, "threads");
  // Each configuration writes only its own row, so the result does not depend on the schedule.
  ThreadPool pool(threads);
  pool.ParallelFor(n, 4, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Profile(clamps.subspan(i * nk, nk), variations[i], out.subspan(i * no, no));
    }
  });
}

std::array<int, 4> SensorModel::VariationSeriesTerms(const SensorVariation& variation) const {
  ValidationError error;
  if (!variation.IsValid(&error)) ThrowInvalid(error);
  std::complex<double> factor;
  std::complex<double> mu;
  return Continuous(variation, &factor, &mu).SeriesTerms(mu);
}

std::size_t SensorModel::VariationPrecomputedBytes() const {
  std::size_t bytes = 0;
  for (const auto& ready : continuous_->ready) {
    const ContinuousCondensation* base = ready.load(std::memory_order_acquire);
    if (base != nullptr) bytes += base->MemoryBytes();
  }
  return bytes;
}

}  // namespace combabc::plate
