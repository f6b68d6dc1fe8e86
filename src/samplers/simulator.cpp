#include "combabc/samplers/simulator.hpp"

#include "combabc/core/check.hpp"

namespace combabc {

void Simulator::SimulateBatch(std::span<const std::uint8_t> bits,
                              std::span<RandomStream> rngs,
                              std::span<double> out) const {
  const std::size_t n = rngs.size();
  if (n == 0) return;
  const std::size_t d = bits.size() / n;
  const std::size_t m = static_cast<std::size_t>(output_size());
  COMBABC_CHECK(bits.size() == n * d && out.size() == n * m);
  for (std::size_t i = 0; i < n; ++i) {
    Simulate(bits.subspan(i * d, d), rngs[i], out.subspan(i * m, m));
  }
}

}  // namespace combabc
