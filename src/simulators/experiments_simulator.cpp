#include "simulators/experiments_simulator.hpp"

#include <algorithm>
#include <cstring>

namespace combabc {

ExperimentsSimulator::ExperimentsSimulator(std::vector<std::unique_ptr<Simulator>> parts)
    : parts_(std::move(parts)) {
  for (const auto& p : parts_) output_size_ += p->output_size();
}

void ExperimentsSimulator::Simulate(const ParameterView& theta,
                                    RandomStream& rng,
                                    std::span<double> out) const {
  std::size_t offset = 0;
  for (const auto& p : parts_) {
    const auto n = static_cast<std::size_t>(p->output_size());
    // Every experiment draws from the candidate's own stream, in experiment order: the same
    // candidate gets the same outputs whatever the batch or thread.
    p->Simulate(theta, rng, out.subspan(offset, n));
    offset += n;
  }
}

void ExperimentsSimulator::SimulateBatch(const ParameterBatch& batch,
                                         std::span<RandomStream> rngs,
                                         std::span<double> out,
                                         BatchFailures& failures) const {
  const auto width = static_cast<std::size_t>(output_size_);
  std::vector<double> part_out;
  std::size_t offset = 0;
  for (const auto& p : parts_) {
    const auto n = static_cast<std::size_t>(p->output_size());
    part_out.assign(batch.count * n, 0.0);
    // Each part sees the whole batch (a worker pool runs it in parallel); a candidate failed by
    // an earlier experiment keeps its first reason.
    std::vector<std::uint8_t> status(batch.count, 0);
    std::vector<char> reasons(batch.count * kFailureReasonBytes, '\0');
    BatchFailures part_failures(status, reasons);
    p->SimulateBatch(batch, rngs, part_out, part_failures);
    for (std::size_t i = 0; i < batch.count; ++i) {
      if (part_failures.failed(i)) {
        if (!failures.failed(i)) failures.Fail(i, part_failures.reason(i));
        continue;
      }
      std::copy_n(part_out.begin() + static_cast<std::ptrdiff_t>(i * n),
                  n,
                  out.begin() + static_cast<std::ptrdiff_t>(i * width + offset));
    }
    offset += n;
  }
}

}  // namespace combabc
