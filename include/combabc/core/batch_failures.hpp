#pragma once
// Which candidates of a batch failed, and why: written by the simulator (a candidate it could not
// simulate) and by the distance (one it could not measure), read by the sampler. Here, below both,
// so that each layer reports a candidate's failure the same way.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace combabc {

// Longest failure reason kept, in bytes: a batch holds each candidate's reason in a fixed-size row
// (so that a distributed executor can gather it like any other result); longer ones are cut.
inline constexpr std::size_t kFailureReasonBytes = 200;

// A view on two per-candidate rows of the batch's result buffers, status (0 = simulated, 1 =
// failed) and the reason, NUL-padded and cut to kFailureReasonBytes - 1 bytes (at a UTF-8
// character boundary). A vectorising SimulateBatch or EvaluateBatch marks single candidates failed
// with Fail(i, reason) instead of throwing for the whole batch.
class BatchFailures {
 public:
  BatchFailures(std::span<std::uint8_t> status, std::span<char> reasons)
      : status_(status), reasons_(reasons) {}
  std::size_t size() const { return status_.size(); }
  void Fail(std::size_t i, std::string_view reason);
  bool failed(std::size_t i) const { return status_[i] != 0; }
  std::string_view reason(std::size_t i) const;
  // The candidates [begin, begin + count), for a simulator handing part of a batch on.
  BatchFailures Sub(std::size_t begin, std::size_t count) const {
    return {status_.subspan(begin, count),
            reasons_.subspan(begin * kFailureReasonBytes, count * kFailureReasonBytes)};
  }

 private:
  std::span<std::uint8_t> status_;
  std::span<char> reasons_;
};

}  // namespace combabc
