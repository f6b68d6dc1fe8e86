#include "combabc/core/batch_failures.hpp"

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

}  // namespace combabc
