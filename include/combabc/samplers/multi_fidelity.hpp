#pragma once
// Multi-fidelity ABC-SMC (Prescott & Baker, "Multifidelity approximate Bayesian computation with
// sequential Monte Carlo parameter sampling", SIAM/ASA JUQ 2021, arXiv:2001.06256): every
// candidate runs a cheap (low-fidelity) simulator; the expensive one runs only with a
// continuation probability that depends on whether the cheap distance accepted. docs/algorithm.md,
// "Multi-fidelity sampling".
#include <string>

#include "combabc/core/validation_error.hpp"

namespace combabc {

struct MultiFidelityOptions {
  // eta_1: the probability of running the expensive simulator on a candidate the cheap one
  // accepted. 1 (the default) never lets a false positive of the cheap model through unchecked,
  // so that no weight is negative.
  double continue_if_accepted = 1.0;
  // eta_2: the same for a candidate the cheap one rejected (a false negative is found with this
  // probability and then weighs 1 / eta_2).
  double continue_if_rejected = 0.1;
  // Tune both, each wave after the first, from the previous wave to maximise the effective sample
  // size per unit cost (the two values above are then the first wave's only).
  bool adapt = true;
  // The least continuation probability tuning may choose, in (0, 1]: it bounds the multiplier of
  // a confirmed candidate by 1 / floor, and keeps each class of candidates confirmed often
  // enough that the cheap model's errors are seen. 0.1, not the paper's 0.01: at 0.01 a wave of
  // a few hundred particles often confirms none of the cheap model's false positives, and its
  // answer is then the cheap model's (docs/algorithm.md, "Multi-fidelity sampling").
  double floor = 0.1;
  // The cost of one expensive simulation over one cheap one, > 0; 0: measured, from the previous
  // waves' summed call times (not deterministic: set it for bit-for-bit reproducible runs).
  double cost_ratio = 0.0;

  // The continuation probabilities and the floor in (0, 1] (a continuation probability of 0
  // would leave the estimator biased: the weight divides by it); cost_ratio finite and >= 0.
  // On failure `error` names the field (owner "MultiFidelityOptions").
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "MultiFidelityOptions::field = value; constraint".
  bool IsValid(std::string* why) const;
};

// The most particles a multi-fidelity wave keeps, per particle it needs (n_t, AcceptedIn): its
// signed multipliers count (sum m)^2 / sum m^2 effective particles, which a cheap model whose
// acceptances the expensive one mostly rejects keeps near zero however many particles the wave
// holds (a wave of 200 grew to 842,019 particles, 2.2 GB). At this many the run stops
// (too_many_particles, docs/algorithm.md "Multi-fidelity sampling"), and the memory
// estimate of a multi-fidelity run counts this many particles per wave. An effective count of
// 1/20 of the particles is what eta_1 at the default floor (0.1) leaves when the expensive model
// confirms about half of the cheap model's acceptances.
inline constexpr int kMultiFidelityParticlesPerAccepted = 20;

// The candidate's multi-fidelity weight multiplier (Prescott & Baker 2020, JUQ 8(1)):
// 1(cheap accepted) + 1(continued) / eta * [1(expensive accepted) - 1(cheap accepted)], with
// eta the continuation probability of the cheap outcome. Its expectation over the continuation is
// 1(expensive accepted), so weighting a candidate by it (times the usual importance weight)
// estimates the expensive model's ABC posterior. It is negative for a cheap acceptance that the
// expensive model rejected when continue_if_accepted < 1; 0 means the candidate carries no weight.
double MultiFidelityMultiplier(const MultiFidelityOptions& options,
                               bool cheap_accepted,
                               bool continued,
                               bool expensive_accepted);

}  // namespace combabc
