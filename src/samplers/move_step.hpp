#pragma once
// The pieces of a resample-move wave that do not need the run (docs/algorithm.md,
// "Resample-move"): resampling, the Metropolis-Hastings proposals on a binary (and real) space,
// the number of rounds, and the step that keeps a fraction of the effective sample size.
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

// Systematic resampling (Carpenter, Clifford & Fearnhead 1999): n indices into `weights` (>= 0,
// sum > 0), non-decreasing, index i appearing about n w_i / sum(w) times, from one uniform u in
// [0, 1). Lower variance than multinomial resampling and deterministic given u.
std::vector<std::size_t> SystematicResample(std::span<const double> weights,
                                            std::size_t n,
                                            double u);

// (sum w)^2 / sum w^2 of weights >= 0; 0 when all are 0.
double EffectiveSampleSize(std::span<const double> weights);

// The largest step in [0, 1] whose weights keep an effective sample size of at least `wanted`
// (`keeps`), and the smallest above it that does not (`loses`; equal to keeps when the full step
// keeps enough): `weights_at(step)` gives the particles' weights for a step (the full step at
// 1), whose ESS is assumed to fall as the step grows (bisection, 40 halvings). keeps = 0 when
// even the smallest step does not keep enough.
struct EssStep {
  double keeps = 1.0;
  double loses = 1.0;
};
EssStep StepKeepingEss(const std::function<std::vector<double>(double)>& weights_at, double wanted);

// Rounds of Metropolis-Hastings steps after which a particle has moved at least once with
// probability 1 - stay at acceptance rate `rate` (Drovandi & Pettitt 2011:
// ceil(log stay / log(1 - rate))), within [1, max_rounds].
int RoundsNeeded(double rate, double stay, int max_rounds);

// What a move proposed for one particle.
struct MoveProposal {
  // log q(old | new) - log q(new | old): 0 for the symmetric local moves.
  double log_q_ratio = 0.0;
  bool independent = false;  // drawn from the fitted kernel
  // The proposed reals lie outside the prior's support: rejected without simulating.
  bool outside_prior = false;
};

// The Metropolis-Hastings proposals of one resample-move wave, fixed before its rounds. With
// probability independent_share a particle proposes from `fitted` (an independent proposal, whose
// ratio needs its density at both points); otherwise a local move: one free bit flipped, or two,
// or (with reals) a Gaussian random walk on the reals. Which bit to flip is drawn from weights
// that do not depend on the particle (the population's uncertainty of each bit, and for the second
// bit its correlation with the first), so a flip's reverse is as likely as the flip: the local
// moves are symmetric.
class MoveProposals {
 public:
  // `population`: the reweighted particles (their free bits, reals and normalised weights);
  // `fitted` may be null (then every move is local). `independent_share` in [0, 1].
  // `ancestor` (may be null): a second independent proposal, the ancestor kernel fitted to the
  // same particles (a mixture of small moves around each), which proposes what the particles hold
  // -- other modes included -- where a product kernel cannot; half the independent proposals
  // come from it.
  MoveProposals(const Population& population,
                const ParameterSpace& space,
                const JointProposal* fitted,
                const JointProposal* ancestor,
                double independent_share);

  // Draws a proposal for a particle at (free, reals) into (new_free, new_reals).
  MoveProposal Propose(RandomStream& rng,
                       std::span<const std::uint8_t> free,
                       std::span<const double> reals,
                       std::span<std::uint8_t> new_free,
                       std::span<double> new_reals) const;

 private:
  std::size_t Draw(RandomStream& rng, std::span<const double> cumulative) const;

  const ParameterSpace& space_;
  const JointProposal* fitted_;
  const JointProposal* ancestor_;
  double independent_share_;
  std::size_t f_, r_;
  std::vector<double> first_;   // cumulative weights of the first bit to flip
  std::vector<double> second_;  // per first bit j, f cumulative weights of the second (row j)
  std::vector<double> step_;    // the random walk's standard deviation per real
};

}  // namespace combabc
