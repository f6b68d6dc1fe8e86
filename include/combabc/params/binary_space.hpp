#pragma once
// The parameter space {0,1}^d with an independent Bernoulli prior, optionally reparameterised by
// tied groups (bits constrained equal, e.g. the left/right clamp symmetry the paper's conclusion
// proposes). Inference runs over the *free* parameters: one per tied group plus one per untied bit.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "combabc/core/validation_error.hpp"

namespace combabc {

// Most bits a space may have where a user declares them: the config's [simulator.bits] count /
// names (the sensor's 2 x 1000 clamps stay below it) and the Python module's BinarySpace.
inline constexpr int kMaxBits = 4096;

struct BinarySpaceOptions {
  int dimension = 0;                   // d, number of bits; 0: a continuous-only space
  std::vector<double> prior_one;       // P(bit = 1) per bit; empty = default_prior_one for all
  double default_prior_one = 0.5;      // used when prior_one is empty
  std::vector<std::vector<int>> tied;  // groups of 0-based bit indices constrained equal
  std::vector<std::string> names;      // optional bit names (e.g. "clamp 1"); empty = "bit k"

  // On failure `error` names the field (owner "BinarySpaceOptions"): "prior_one[3]", "tied[1]".
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "BinarySpaceOptions::field = value; constraint".
  bool IsValid(std::string* why) const;
};

class BinarySpace {
 public:
  // Throws combabc::Error(kConfig) naming the field if options are invalid.
  explicit BinarySpace(const BinarySpaceOptions& options);
  static BinarySpace Independent(int dimension, double prior_one = 0.5);

  int dimension() const { return static_cast<int>(free_of_bit_.size()); }
  int num_free() const { return static_cast<int>(free_prior_one_.size()); }
  // P(free parameter j = 1) under the prior. For a tied group with bit priors p_i this is the
  // prior conditioned on the constraint: prod p_i / (prod p_i + prod (1 - p_i)).
  const std::vector<double>& free_prior_one() const { return free_prior_one_; }
  // Prior P(bit = 1) of every bit after the tie constraint.
  std::vector<double> bit_prior_one() const;
  // Index of the free parameter that drives bit k.
  int free_of_bit(int bit) const { return free_of_bit_[bit]; }
  const std::string& name(int bit) const { return names_[bit]; }

  // Full bit vector (size d) from free parameters (size num_free()).
  void Expand(std::span<const std::uint8_t> free, std::span<std::uint8_t> bits) const;
  // Free parameters from a full bit vector; false if the bits violate a tie.
  bool Reduce(std::span<const std::uint8_t> bits, std::span<std::uint8_t> free) const;

 private:
  std::vector<int> free_of_bit_;
  std::vector<double> free_prior_one_;
  std::vector<std::string> names_;
};

// Whether any of these priors P(bit = 1) is neither 0 nor 1: a bit the data can inform. A fixed or
// dummy bit (prior 0 or 1) is a constant to the kernels, so it does not make a space mixed.
bool AnyUncertainBit(std::span<const double> prior_one);

}  // namespace combabc
