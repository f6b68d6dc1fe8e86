#include "combabc/params/binary_space.hpp"

#include <algorithm>
#include <cmath>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc {

bool BinarySpaceOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool BinarySpaceOptions::IsValid(ValidationError* error) const {
  // fail(field, value, constraint); with no value, constraint is what follows the field.
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rest) {
    if (error) *error = {"BinarySpaceOptions", field, value, rest};
    return false;
  };
  // Zero bits is a continuous-only space: the binary part is then one empty configuration.
  if (dimension < 0) return fail("dimension", std::to_string(dimension), "must be >= 0");
  if (!prior_one.empty() && static_cast<int>(prior_one.size()) != dimension) {
    return fail("prior_one",
                "",
                "has " + std::to_string(prior_one.size()) +
                    " entries; must have dimension = " + std::to_string(dimension));
  }
  // A prior of exactly 0 or 1 fixes the bit: allowed, but the bit then carries no information.
  auto bad_prob = [](double p) { return !(p >= 0.0 && p <= 1.0); };
  if (bad_prob(default_prior_one)) {
    return fail("default_prior_one", std::to_string(default_prior_one), "must be in [0, 1]");
  }
  for (std::size_t k = 0; k < prior_one.size(); ++k) {
    if (bad_prob(prior_one[k])) {
      return fail("prior_one[" + std::to_string(k) + "]",
                  std::to_string(prior_one[k]),
                  "must be in [0, 1]");
    }
  }
  if (!names.empty() && static_cast<int>(names.size()) != dimension) {
    return fail("names",
                "",
                "has " + std::to_string(names.size()) +
                    " entries; must have dimension = " + std::to_string(dimension));
  }
  std::vector<int> group_of(static_cast<std::size_t>(dimension), -1);
  for (std::size_t g = 0; g < tied.size(); ++g) {
    const std::string where = "tied[" + std::to_string(g) + "]";
    if (tied[g].size() < 2) return fail(where, "", "has fewer than 2 bits; a tie needs at least 2");
    for (int bit : tied[g]) {
      if (bit < 0 || bit >= dimension) {
        return fail(where,
                    "",
                    "contains bit " + std::to_string(bit) + "; must be in [0, " +
                        std::to_string(dimension - 1) + "]");
      }
      if (group_of[bit] >= 0) {
        return fail(where,
                    "",
                    "contains bit " + std::to_string(bit) + ", already in tied[" +
                        std::to_string(group_of[bit]) + "]; groups must be disjoint");
      }
      group_of[bit] = static_cast<int>(g);
    }
    double all_one = 1.0, all_zero = 1.0;
    for (int bit : tied[g]) {
      const double p = prior_one.empty() ? default_prior_one : prior_one[bit];
      all_one *= p;
      all_zero *= 1.0 - p;
    }
    if (all_one + all_zero <= 0.0) {
      return fail(where, "", "has zero prior mass: its bits' priors cannot all be equal");
    }
  }
  return true;
}

BinarySpace::BinarySpace(const BinarySpaceOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error(ErrorKind::kConfig, why);
  const int d = options.dimension;
  auto prior = [&](int bit) {
    return options.prior_one.empty() ? options.default_prior_one : options.prior_one[bit];
  };
  free_of_bit_.assign(static_cast<std::size_t>(d), -1);
  // Free parameters are numbered in order of their lowest bit, so an untied space maps bit k to
  // free parameter k.
  std::vector<int> group_of(static_cast<std::size_t>(d), -1);
  for (std::size_t g = 0; g < options.tied.size(); ++g) {
    for (int bit : options.tied[g]) group_of[bit] = static_cast<int>(g);
  }
  std::vector<int> free_of_group(options.tied.size(), -1);
  for (int bit = 0; bit < d; ++bit) {
    const int g = group_of[bit];
    if (g >= 0 && free_of_group[g] >= 0) {
      free_of_bit_[bit] = free_of_group[g];
      continue;
    }
    const int j = static_cast<int>(free_prior_one_.size());
    free_of_bit_[bit] = j;
    if (g < 0) {
      free_prior_one_.push_back(prior(bit));
    } else {
      free_of_group[g] = j;
      // The prior restricted to {all 0, all 1} and renormalised.
      double all_one = 1.0, all_zero = 1.0;
      for (int b : options.tied[g]) {
        all_one *= prior(b);
        all_zero *= 1.0 - prior(b);
      }
      free_prior_one_.push_back(all_one / (all_one + all_zero));
    }
  }
  names_ = options.names;
  if (names_.empty()) {
    for (int bit = 0; bit < d; ++bit) names_.push_back("bit " + std::to_string(bit + 1));
  }
}

BinarySpace BinarySpace::Independent(int dimension, double prior_one) {
  BinarySpaceOptions options;
  options.dimension = dimension;
  options.default_prior_one = prior_one;
  return BinarySpace(options);
}

std::vector<double> BinarySpace::bit_prior_one() const {
  std::vector<double> out(free_of_bit_.size());
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = free_prior_one_[free_of_bit_[k]];
  return out;
}

bool AnyUncertainBit(std::span<const double> prior_one) {
  return std::any_of(
      prior_one.begin(), prior_one.end(), [](double p) { return p > 0.0 && p < 1.0; });
}

void BinarySpace::Expand(std::span<const std::uint8_t> free, std::span<std::uint8_t> bits) const {
  COMBABC_CHECK(free.size() == free_prior_one_.size() && bits.size() == free_of_bit_.size());
  for (std::size_t k = 0; k < bits.size(); ++k) bits[k] = free[free_of_bit_[k]];
}

bool BinarySpace::Reduce(std::span<const std::uint8_t> bits, std::span<std::uint8_t> free) const {
  COMBABC_CHECK(free.size() == free_prior_one_.size() && bits.size() == free_of_bit_.size());
  std::vector<int> seen(free.size(), 0);
  for (std::size_t k = 0; k < bits.size(); ++k) {
    const int j = free_of_bit_[k];
    if (seen[j] && free[j] != bits[k]) return false;
    free[j] = bits[k];
    seen[j] = 1;
  }
  return true;
}

}  // namespace combabc
