#pragma once
// A mixed parameter space: bits (a BinarySpace, with its ties and Bernoulli prior) followed by
// continuous parameters, each with its own prior or a coordinate of a joint prior over a group.
// Inference runs over the free bits and the reals; ParameterValue carries the full bit vector and
// the reals.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "combabc/params/binary_space.hpp"
#include "combabc/params/continuous_prior.hpp"
#include "combabc/params/joint_prior.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

// The prior of the reals: independent priors and joint priors over groups. Cheap to copy (the
// joint priors are shared), so that a proposal, which may outlive its space, keeps its own.
// Built and checked by ParameterSpace.
class RealsPrior {
 public:
  struct Group {
    std::vector<std::size_t> index;  // the reals it covers, in its coordinates' order
    std::shared_ptr<const JointPrior> prior;
  };
  RealsPrior() = default;
  RealsPrior(std::vector<ContinuousPrior> marginals,
             std::vector<std::string> names,
             std::vector<Group> groups);

  std::size_t dimension() const { return marginals_.size(); }
  // Real k's own prior, or for kJoint its bounds and moments.
  const ContinuousPrior& marginal(std::size_t k) const { return marginals_[k]; }
  // log p of the reals; -infinity outside the support.
  double LogDensity(std::span<const double> reals) const;
  // Inside every real's bounds, and of positive joint density.
  bool InSupport(std::span<const double> reals) const;
  // One draw of every real, in order (a group at its first real), using only `rng`. Throws
  // combabc::Error(kConfig) naming the real when a joint prior's sampler leaves its bounds.
  void Sample(RandomStream& rng, std::span<double> reals) const;

 private:
  // The group's coordinates of `reals`, gathered into `scratch` unless they are contiguous.
  std::span<const double> Gather(const Group& g,
                                 std::span<const double> reals,
                                 std::vector<double>& scratch) const;

  std::vector<ContinuousPrior> marginals_;
  std::vector<std::string> names_;
  std::vector<Group> groups_;
  std::vector<int> group_of_;  // -1: an independent prior
};

class ParameterSpace {
 public:
  // Throws combabc::Error(kConfig) naming the parameter if a prior is invalid, two parameters
  // share a name, or a joint prior does not fit its reals (every kJoint real belongs to exactly one
  // group; CheckJointPrior passes). A kJoint real's mean and sd are set from its sampler.
  explicit ParameterSpace(BinarySpace bits,
                          std::vector<ContinuousParameter> reals = {},
                          std::vector<JointPriorGroup> joint = {});

  const BinarySpace& binary() const { return bits_; }
  int num_bits() const { return bits_.dimension(); }
  int num_free_bits() const { return bits_.num_free(); }
  int num_reals() const { return static_cast<int>(reals_.size()); }
  const std::vector<ContinuousParameter>& reals() const { return reals_; }
  const std::vector<JointPriorGroup>& joint_priors() const { return joint_; }
  const RealsPrior& reals_prior() const { return reals_prior_; }

  // log p of the free bits under the (tie-conditioned) Bernoulli prior.
  double LogPriorBits(std::span<const std::uint8_t> free_bits) const;
  // log p of the reals; -infinity outside the support.
  double LogPriorReals(std::span<const double> reals) const {
    return reals_prior_.LogDensity(reals);
  }
  bool InSupport(std::span<const double> reals) const { return reals_prior_.InSupport(reals); }

 private:
  // Matches the joint priors to their kJoint reals, checks each (CheckJointPrior), sets the reals'
  // moments and builds reals_prior_.
  void CheckJointPriors();

  BinarySpace bits_;
  std::vector<ContinuousParameter> reals_;
  std::vector<JointPriorGroup> joint_;
  RealsPrior reals_prior_;
  // log prior of free bit j = v at [2 j + v]: a lookup, not a branch on random bits.
  std::vector<double> log_density_;
};

}  // namespace combabc
