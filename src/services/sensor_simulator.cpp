#include "combabc/services/sensor_simulator.hpp"

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc::services {

SensorSimulator::SensorSimulator(const plate::SensorOptions& options,
                                 std::vector<std::string> real_names)
    : model_(options), real_names_(std::move(real_names)) {
  for (const auto& name : real_names_) {
    const plate::SensorVariationField* field = plate::FindSensorVariationField(name);
    if (field == nullptr) {
      throw Error(ErrorKind::kConfig,
                  "the sensor model has no continuous parameter " + Excerpt(name),
                  "",
                  0,
                  "parameters." + name);
    }
    members_.push_back(field->member);
  }
}

plate::SensorVariation SensorSimulator::Variation(std::span<const double> reals) const {
  COMBABC_CHECK(reals.size() == members_.size());
  plate::SensorVariation v;
  for (std::size_t k = 0; k < reals.size(); ++k) v.*members_[k] = reals[k];
  return v;
}

void SensorSimulator::Simulate(const ParameterView& theta,
                               RandomStream& /*rng*/,
                               std::span<double> out) const {
  // A configuration the plate cannot be solved in is that candidate's failure, with its reason.
  try {
    if (real_names_.empty()) {
      model_.Profile(theta.bits, out);
    } else {
      model_.Profile(theta.bits, Variation(theta.reals), out);
    }
  } catch (const plate::SingularSystem& singular) {
    throw SimulationFailed(singular.message(), ErrorKind::kConfig);
  }
}

void SensorSimulator::SimulateBatch(const ParameterBatch& batch,
                                    std::span<RandomStream> rngs,
                                    std::span<double> out,
                                    BatchFailures& failures) const {
  if (!real_names_.empty()) {
    Simulator::SimulateBatch(batch, rngs, out, failures);  // one variation per candidate
    return;
  }
  // One thread here: the engine already runs one batch per worker thread.
  const std::size_t no = static_cast<std::size_t>(model_.num_outputs());
  for (std::size_t i = 0; i < batch.count; ++i) {
    try {
      model_.Profile(batch[i].bits, out.subspan(i * no, no));
    } catch (const plate::SingularSystem& singular) {
      failures.Fail(i, singular.message());
    }
  }
}

}  // namespace combabc::services
