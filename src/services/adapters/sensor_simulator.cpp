#include "combabc/services/adapters/sensor_simulator.hpp"

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc::services {

SensorSimulator::SensorSimulator(const std::vector<SensorModelPlan>& plans,
                                 std::vector<std::string> real_names,
                                 const plate::PrecomputeOptions& precompute)
    : real_names_(std::move(real_names)) {
  COMBABC_CHECK(!plans.empty());
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
  // Each experiment's first output in the simulator's output (experiment order).
  std::size_t experiments = 0;
  for (const SensorModelPlan& plan : plans) experiments += plan.experiments.size();
  std::vector<std::size_t> sizes(experiments, 0);
  for (const SensorModelPlan& plan : plans) {
    for (std::size_t c = 0; c < plan.experiments.size(); ++c) {
      sizes.at(plan.experiments[c]) = plan.options.load_cases[c].output_positions.size();
    }
  }
  std::vector<std::size_t> offsets(experiments + 1, 0);
  for (std::size_t e = 0; e < experiments; ++e) offsets[e + 1] = offsets[e] + sizes[e];
  output_size_ = static_cast<int>(offsets.back());
  for (const SensorModelPlan& plan : plans) {
    Model m;
    m.model = std::make_unique<plate::SensorModel>(plan.options, precompute);
    bool in_order = plans.size() == 1;
    for (std::size_t c = 0; c < plan.experiments.size(); ++c) {
      in_order = in_order && plan.experiments[c] == c;
      const std::size_t begin = offsets[plan.experiments[c]];
      for (std::size_t k = 0; k < sizes[plan.experiments[c]]; ++k) m.scatter.push_back(begin + k);
    }
    if (in_order) m.scatter.clear();
    models_.push_back(std::move(m));
  }
}

plate::SensorVariation SensorSimulator::Variation(std::span<const double> reals) const {
  COMBABC_CHECK(reals.size() == members_.size());
  plate::SensorVariation v;
  for (std::size_t k = 0; k < reals.size(); ++k) v.*members_[k] = reals[k];
  return v;
}

void SensorSimulator::Profile(std::span<const std::uint8_t> bits,
                              const plate::SensorVariation* variation,
                              std::span<double> out) const {
  thread_local std::vector<double> buffer;
  for (const Model& m : models_) {
    std::span<double> target = out;
    if (!m.scatter.empty()) {
      buffer.resize(m.scatter.size());
      target = buffer;
    }
    if (variation == nullptr) {
      m.model->Profile(bits, target);
    } else {
      m.model->Profile(bits, *variation, target);
    }
    for (std::size_t k = 0; k < m.scatter.size(); ++k) out[m.scatter[k]] = buffer[k];
  }
}

void SensorSimulator::Simulate(const ParameterView& theta,
                               RandomStream& /*rng*/,
                               std::span<double> out) const {
  // A configuration the plate cannot be solved in is that candidate's failure, with its reason.
  try {
    if (real_names_.empty()) {
      Profile(theta.bits, nullptr, out);
    } else {
      const plate::SensorVariation variation = Variation(theta.reals);
      Profile(theta.bits, &variation, out);
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
  const auto no = static_cast<std::size_t>(output_size_);
  for (std::size_t i = 0; i < batch.count; ++i) {
    try {
      Profile(batch[i].bits, nullptr, out.subspan(i * no, no));
    } catch (const plate::SingularSystem& singular) {
      failures.Fail(i, singular.message());
    }
  }
}

}  // namespace combabc::services
