#pragma once
// One point of a parameter space: the full bit vector (the clamps) and the continuous values
// (stiffness, damping, ...). The one value type simulators, the history, the export and the
// metrics see; ParameterView borrows one, ParameterBatch a row-major block of them.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace combabc {

struct ParameterView {
  std::span<const std::uint8_t> bits;  // 0/1, ParameterSpace::num_bits() entries
  std::span<const double> reals;       // ParameterSpace::num_reals() entries, SI units
};

struct ParameterValue {
  std::vector<std::uint8_t> bits;
  std::vector<double> reals;

  ParameterView view() const { return {bits, reals}; }
  bool operator==(const ParameterValue&) const = default;
};

// n parameter values stored row-major: bits n x num_bits, reals n x num_reals.
struct ParameterBatch {
  std::size_t count = 0;
  std::size_t num_bits = 0;
  std::size_t num_reals = 0;
  std::span<const std::uint8_t> bits;
  std::span<const double> reals;

  ParameterView operator[](std::size_t i) const {
    return {bits.subspan(i * num_bits, num_bits), reals.subspan(i * num_reals, num_reals)};
  }
};

}  // namespace combabc
