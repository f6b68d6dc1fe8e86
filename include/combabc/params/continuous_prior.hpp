#pragma once
// Priors of continuous parameters (Toni et al. 2009; Beaumont et al. 2009): uniform, normal,
// lognormal and truncated normal. Each has a log density (for importance weights), a sampler that
// draws from the candidate's own RandomStream, and a support (a proposal outside it has prior
// density 0 and is drawn again).
#include <string>

#include "combabc/core/enum_names.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

enum class PriorKind {
  kUniform,          // on [low, high]
  kNormal,           // N(mean, sd^2)
  kLogNormal,        // log x ~ N(mean, sd^2): mean and sd are of log x
  kTruncatedNormal,  // N(mean, sd^2) restricted to [low, high]
};
template <>
struct EnumNames<PriorKind> {
  static constexpr std::pair<PriorKind, const char*> kNames[] = {
      {PriorKind::kUniform, "uniform"},
      {PriorKind::kNormal, "normal"},
      {PriorKind::kLogNormal, "lognormal"},
      {PriorKind::kTruncatedNormal, "truncated_normal"},
  };
};

struct ContinuousPrior {
  PriorKind kind = PriorKind::kUniform;
  double low = 0.0;   // kUniform, kTruncatedNormal
  double high = 1.0;  // kUniform, kTruncatedNormal
  double mean = 0.0;  // kNormal, kTruncatedNormal; of log x for kLogNormal
  double sd = 1.0;    // likewise; > 0

  // Finite parameters, low < high, sd > 0, and for kTruncatedNormal a truncation interval with
  // enough normal mass to sample (at least 1e-12). `why` reads "field = value; constraint".
  bool IsValid(std::string* why) const;
  // Normalised log density; -infinity outside the support.
  double LogDensity(double x) const;
  bool InSupport(double x) const;
  // One draw, using only `rng`.
  double Sample(RandomStream& rng) const;
  // Mean and standard deviation of the prior (for reports, tests and initial scales).
  double Mean() const;
  double StandardDeviation() const;
};

struct ContinuousParameter {
  std::string name;  // e.g. "foundation_stiffness"
  ContinuousPrior prior;
};

}  // namespace combabc
