#include "simulators/selected_outputs.hpp"

#include <cstddef>
#include <utility>

namespace combabc {

SelectedOutputs::SelectedOutputs(std::unique_ptr<Simulator> inner, std::vector<int> picks)
    : inner_(std::move(inner)), picks_(std::move(picks)) {}

void SelectedOutputs::Simulate(const ParameterView& theta,
                               RandomStream& rng,
                               std::span<double> out) const {
  std::vector<double> all(static_cast<std::size_t>(inner_->output_size()));
  inner_->Simulate(theta, rng, all);
  for (std::size_t k = 0; k < picks_.size(); ++k) {
    out[k] = all[static_cast<std::size_t>(picks_[k])];
  }
}

void SelectedOutputs::SimulateBatch(const ParameterBatch& batch,
                                    std::span<RandomStream> rngs,
                                    std::span<double> out,
                                    BatchFailures& failures) const {
  const auto width = static_cast<std::size_t>(inner_->output_size());
  std::vector<double> all(batch.count * width);
  // The inner simulator's own batch form: a worker pool or the sensor's batched solve.
  inner_->SimulateBatch(batch, rngs, all, failures);
  for (std::size_t i = 0; i < batch.count; ++i) {
    for (std::size_t k = 0; k < picks_.size(); ++k) {
      out[i * picks_.size() + k] = all[i * width + static_cast<std::size_t>(picks_[k])];
    }
  }
}

}  // namespace combabc
