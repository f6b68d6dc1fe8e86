#include "combabc/samplers/simulator.hpp"

#include "combabc/core/check.hpp"

namespace combabc {

void Simulator::SimulateBatch(const ParameterBatch& batch,
                              std::span<RandomStream> rngs,
                              std::span<double> out,
                              BatchFailures& failures) const {
  const std::size_t n = batch.count;
  const std::size_t m = static_cast<std::size_t>(output_size());
  COMBABC_CHECK(rngs.size() == n && out.size() == n * m && failures.size() == n);
  for (std::size_t i = 0; i < n; ++i) {
    try {
      Simulate(batch[i], rngs[i], out.subspan(i * m, m));
    } catch (const SimulationFailed& e) {
      failures.Fail(i, e.what());
    }
  }
}

}  // namespace combabc
