#pragma once
// Priors of continuous parameters (Toni et al. 2009; Beaumont et al. 2009): uniform, normal,
// lognormal and truncated normal. Each has a log density (for importance weights), a sampler that
// draws from the candidate's own RandomStream, and a support (a proposal outside it has prior
// density 0 and is drawn again). A real may instead belong to a joint prior (joint_prior.hpp),
// whose density and sampler cover a group of reals: ParameterSpace holds it.
#include <string>

#include "combabc/core/enum_names.hpp"
#include "combabc/core/validation_error.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

enum class PriorKind {
  kUniform,          // on [low, high]
  kNormal,           // N(mean, sd^2)
  kLogNormal,        // log x ~ N(mean, sd^2): mean and sd are of log x
  kTruncatedNormal,  // N(mean, sd^2) restricted to [low, high]
  kJoint,            // a coordinate of a JointPrior (ParameterSpace's joint priors), in [low, high]
};
template <>
struct EnumNames<PriorKind> {
  static constexpr std::pair<PriorKind, const char*> kNames[] = {
      {PriorKind::kUniform, "uniform"},
      {PriorKind::kNormal, "normal"},
      {PriorKind::kLogNormal, "lognormal"},
      {PriorKind::kTruncatedNormal, "truncated_normal"},
      {PriorKind::kJoint, "joint"},
  };
};

struct ContinuousPrior {
  PriorKind kind = PriorKind::kUniform;
  double low = 0.0;   // kUniform, kTruncatedNormal; kJoint (may be -inf)
  double high = 1.0;  // kUniform, kTruncatedNormal; kJoint (may be +inf)
  double mean = 0.0;  // kNormal, kTruncatedNormal; of log x for kLogNormal; kJoint: see below
  double sd = 1.0;    // likewise; > 0
  // kJoint: mean and sd are the coordinate's mean and sd estimated from the joint prior's sampler,
  // set by ParameterSpace (for reports, the history and the kernels' initial scales).

  // Finite parameters, low < high, sd > 0, and for kTruncatedNormal a truncation interval with
  // enough normal mass to sample (at least 1e-12); kJoint allows infinite bounds. Fills `error`
  // (may be null) with the first field that fails, without an owner (the caller names the prior).
  bool IsValid(ValidationError* error) const;
  // The same check as a sentence: "field = value; constraint".
  bool IsValid(std::string* why) const;
  // Normalised log density; -infinity outside the support. Not for kJoint (a coordinate of a joint
  // prior has no density of its own: ParameterSpace::LogPriorReals).
  double LogDensity(double x) const;
  bool InSupport(double x) const;
  // One draw, using only `rng`. Not for kJoint (ParameterSpace::SampleReals).
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
