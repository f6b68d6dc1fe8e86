#include "combabc/params/parameter_space.hpp"

#include <cmath>
#include <set>
#include <utility>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc {

ParameterSpace::ParameterSpace(BinarySpace bits, std::vector<ContinuousParameter> reals)
    : bits_(std::move(bits)), reals_(std::move(reals)) {
  // Zero bits is a continuous-only space; zero of both has nothing to infer.
  if (bits_.dimension() == 0 && reals_.empty()) {
    throw Error(ErrorKind::kConfig,
                "the space has no parameters: declare at least one bit or one real parameter");
  }
  // Bit names share the namespace: histories, exports and reports name every parameter, so a real
  // called like a bit would make them ambiguous.
  std::set<std::string> bit_names;
  for (int bit = 0; bit < bits_.dimension(); ++bit) bit_names.insert(bits_.name(bit));
  std::set<std::string> seen;
  for (std::size_t k = 0; k < reals_.size(); ++k) {
    const ContinuousParameter& p = reals_[k];
    const std::string field = "reals[" + std::to_string(k) + "] (" + p.name + ")";
    if (p.name.empty()) {
      throw Error(ErrorKind::kConfig, "name is empty; every parameter needs a name", "", 0, field);
    }
    if (!seen.insert(p.name).second) {
      throw Error(
          ErrorKind::kConfig,
          "name '" + p.name + "' is used by an earlier real parameter; names must be unique",
          "",
          0,
          field);
    }
    if (bit_names.contains(p.name)) {
      throw Error(ErrorKind::kConfig,
                  "name '" + p.name + "' is also a bit's name; names must be unique",
                  "",
                  0,
                  field);
    }
    std::string why;
    if (!p.prior.IsValid(&why)) {
      throw Error(
          ErrorKind::kConfig, std::string(ToString(p.prior.kind)) + " prior: " + why, "", 0, field);
    }
  }
  // Precomputed once: LogPriorBits runs for every candidate of every wave.
  for (const double p : bits_.free_prior_one()) {
    log_density_.push_back(std::log1p(-p));
    log_density_.push_back(std::log(p));
  }
}

double ParameterSpace::LogPriorBits(std::span<const std::uint8_t> free_bits) const {
  COMBABC_CHECK(2 * free_bits.size() == log_density_.size());
  double sum = 0.0;
  for (std::size_t j = 0; j < free_bits.size(); ++j) {
    sum += log_density_[2 * j + (free_bits[j] & 1U)];
  }
  return sum;
}

double ParameterSpace::LogPriorReals(std::span<const double> reals) const {
  COMBABC_CHECK(reals.size() == reals_.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < reals.size(); ++k) sum += reals_[k].prior.LogDensity(reals[k]);
  return sum;
}

bool ParameterSpace::InSupport(std::span<const double> reals) const {
  COMBABC_CHECK(reals.size() == reals_.size());
  for (std::size_t k = 0; k < reals.size(); ++k) {
    if (!reals_[k].prior.InSupport(reals[k])) return false;
  }
  return true;
}

}  // namespace combabc
