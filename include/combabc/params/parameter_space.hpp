#pragma once
// A mixed parameter space: bits (a BinarySpace, with its ties and Bernoulli prior) followed by
// continuous parameters with independent priors. Inference runs over the free bits and the reals;
// ParameterValue carries the full bit vector and the reals.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "combabc/params/binary_space.hpp"
#include "combabc/params/continuous_prior.hpp"

namespace combabc {

class ParameterSpace {
 public:
  // Throws combabc::Error(kConfig) naming the parameter if a prior is invalid or two parameters
  // share a name.
  explicit ParameterSpace(BinarySpace bits, std::vector<ContinuousParameter> reals = {});

  const BinarySpace& binary() const { return bits_; }
  int num_bits() const { return bits_.dimension(); }
  int num_free_bits() const { return bits_.num_free(); }
  int num_reals() const { return static_cast<int>(reals_.size()); }
  const std::vector<ContinuousParameter>& reals() const { return reals_; }

  // log p of the free bits under the (tie-conditioned) Bernoulli prior.
  double LogPriorBits(std::span<const std::uint8_t> free_bits) const;
  // log p of the reals; -infinity outside the support.
  double LogPriorReals(std::span<const double> reals) const;
  bool InSupport(std::span<const double> reals) const;

 private:
  BinarySpace bits_;
  std::vector<ContinuousParameter> reals_;
  // log prior of free bit j = v at [2 j + v]: a lookup, not a branch on random bits.
  std::vector<double> log_density_;
};

}  // namespace combabc
