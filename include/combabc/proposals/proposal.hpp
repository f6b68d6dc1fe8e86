#pragma once
// The proposal seam. A wave proposes candidates from a JointProposal over the free bits and the
// reals; a JointKernel fits the next wave's JointProposal to the previous wave's weighted
// population. One implementation is the product of a binary kernel and a continuous kernel
// (q(b, r) = q_bits(b) q_reals(r): MakeProductKernel); another proposes both from one ancestor
// particle (the ancestor kernel, ancestor_kernel.hpp). See docs/algorithm.md.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "combabc/params/parameter_space.hpp"
#include "combabc/rng/random_stream.hpp"
#include "combabc/schedules/tempering_schedule.hpp"

namespace combabc {

// The previous wave's accepted particles, reduced to free parameters, with the estimator's
// normalised weights (summing to 1).
struct Population {
  std::size_t size = 0;
  std::size_t num_free_bits = 0;
  std::size_t num_reals = 0;
  std::vector<std::uint8_t> free_bits;  // size x num_free_bits, row-major
  std::vector<double> reals;            // size x num_reals, row-major
  std::vector<double> weights;          // size, sum 1
  // 1 where the particle also satisfies the new wave's thresholds (used by OLCM, Filippi et al.
  // 2013, which builds each local covariance from those particles only).
  std::vector<std::uint8_t> within_next;

  std::span<const std::uint8_t> bits_of(std::size_t i) const {
    return {free_bits.data() + i * num_free_bits, num_free_bits};
  }
  std::span<const double> reals_of(std::size_t i) const {
    return {reals.data() + i * num_reals, num_reals};
  }
};

// How the binary proposal is tempered toward the prior (Eq. 3) in this wave.
struct Tempering {
  double phi = 0.0;
  TemperingForm form = TemperingForm::kGeometric;
};

// One wave's proposal over the free bits. Sample and LogDensity are const and thread-safe.
class BinaryProposal {
 public:
  virtual ~BinaryProposal() = default;
  virtual void Sample(RandomStream& rng, std::span<std::uint8_t> free_bits) const = 0;
  // Normalised log q(free_bits): exact, so importance weights p/q are exact. -infinity where
  // q = 0 (never for a value Sample returned).
  virtual double LogDensity(std::span<const std::uint8_t> free_bits) const = 0;
  // P(free bit j = 1) under this proposal (recorded as the wave's proposal; exact for the
  // independent kernel, a fixed-stream Monte-Carlo estimate where no closed form exists).
  virtual std::vector<double> Marginals() const = 0;
};

// Fits binary proposals. `prior_one` is P(free bit = 1) under the prior.
class BinaryKernel {
 public:
  virtual ~BinaryKernel() = default;
  virtual std::string name() const = 0;
  // Wave 0 (and any wave with an empty population): the prior.
  virtual std::unique_ptr<BinaryProposal> Prior(const std::vector<double>& prior_one) const;
  virtual std::unique_ptr<BinaryProposal> Fit(const Population& population,
                                              const std::vector<double>& prior_one,
                                              const Tempering& tempering) const = 0;
};

// One wave's proposal over the reals. Sample returns only points inside the prior's support
// (drawing again, from the same stream, until it finds one; throws combabc::Error(kSoftware) after
// 10^4 tries). LogDensity may omit a normalising constant common to the whole wave (such as the
// mass of the support), which self-normalised weights do not see.
class ContinuousProposal {
 public:
  virtual ~ContinuousProposal() = default;
  virtual void Sample(RandomStream& rng, std::span<double> reals) const = 0;
  virtual double LogDensity(std::span<const double> reals) const = 0;
};

class ContinuousKernel {
 public:
  virtual ~ContinuousKernel() = default;
  virtual std::string name() const = 0;
  // Wave 0: the prior itself.
  virtual std::unique_ptr<ContinuousProposal> Prior(const ParameterSpace& space) const;
  virtual std::unique_ptr<ContinuousProposal> Fit(const Population& population,
                                                  const ParameterSpace& space) const = 0;
};

// One wave's proposal over the free bits and the reals together; what the sampler draws candidates
// from and weighs them by. Every method is const and thread-safe.
class JointProposal {
 public:
  virtual ~JointProposal() = default;
  // Draws free bits, then reals (empty without reals), using only `rng`. The reals are inside the
  // prior's support (drawn again, from the same stream, until they are; throws
  // combabc::Error(kSoftware) after 10^4 tries).
  virtual void Sample(RandomStream& rng,
                      std::span<std::uint8_t> free_bits,
                      std::span<double> reals) const = 0;
  // log q(free_bits, reals), exact up to a constant common to the wave (the mass of the reals'
  // support), so self-normalised importance weights p/q are exact; -infinity where q = 0.
  virtual double LogDensity(std::span<const std::uint8_t> free_bits,
                            std::span<const double> reals) const = 0;
  // log of the proposal's marginal probability of the free-bit pattern (the reals integrated out):
  // normalised, so that it sums to 1 over all patterns. For the mode-loss diagnostic: how likely
  // the wave is to propose the patterns that carry the previous population's mass.
  virtual double LogBitsDensity(std::span<const std::uint8_t> free_bits) const = 0;
  // P(free bit j = 1) under this proposal (recorded as the wave's proposal; exact where a closed
  // form exists, a fixed-stream Monte-Carlo estimate otherwise).
  virtual std::vector<double> Marginals() const = 0;
};

// Fits joint proposals. Tempering applies to the bits (Eq. 3).
class JointKernel {
 public:
  virtual ~JointKernel() = default;
  // What the history records as the proposal kind ("independent", "logistic", "ancestor").
  virtual std::string name() const = 0;
  // Wave 0 (and any wave with an empty population): the prior.
  virtual std::unique_ptr<JointProposal> Prior(const ParameterSpace& space) const = 0;
  virtual std::unique_ptr<JointProposal> Fit(const Population& population,
                                             const ParameterSpace& space,
                                             const Tempering& tempering) const = 0;
};

// q(b, r) = q_bits(b) q_reals(r): each part fitted on its own (`reals` unused by a space without
// reals). Sample draws the bits first, then the reals, from the same stream. Its name() is the
// binary kernel's. Such a proposal draws reals without regard to the bits they go with, so it can
// lose a posterior mode whose pattern needs other reals (docs/algorithm.md).
std::unique_ptr<JointKernel> MakeProductKernel(std::unique_ptr<BinaryKernel> bits,
                                               std::unique_ptr<ContinuousKernel> reals);

// The independent per-bit kernel: Eq. 2 (weighted fractions of 1s), tempered by Eq. 3.
std::unique_ptr<BinaryKernel> MakeIndependentKernel();

}  // namespace combabc
