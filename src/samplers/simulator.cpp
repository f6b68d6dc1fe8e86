#include "combabc/samplers/simulator.hpp"

#include <algorithm>
#include <cstring>

#include "combabc/core/check.hpp"

namespace combabc {

void BatchFailures::Fail(std::size_t i, std::string_view reason) {
  COMBABC_CHECK(i < status_.size());
  status_[i] = 1;
  std::size_t n = std::min(reason.size(), kFailureReasonBytes - 1);
  // Never cut a UTF-8 character in two: back up over continuation bytes (10xxxxxx).
  if (n < reason.size()) {
    while (n > 0 && (static_cast<unsigned char>(reason[n]) & 0xC0U) == 0x80U) --n;
  }
  char* row = reasons_.data() + i * kFailureReasonBytes;
  std::memset(row, 0, kFailureReasonBytes);
  std::memcpy(row, reason.data(), n);
}

std::string_view BatchFailures::reason(std::size_t i) const {
  const char* row = reasons_.data() + i * kFailureReasonBytes;
  return {row, strnlen(row, kFailureReasonBytes)};
}

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
