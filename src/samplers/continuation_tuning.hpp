#pragma once
// The continuation probabilities that maximise a multi-fidelity wave's effective sample size per
// unit cost (Prescott & Baker, "Multifidelity approximate Bayesian computation with sequential
// Monte Carlo parameter sampling", arXiv:2001.06256, section 3.3; docs/algorithm.md,
// "Multi-fidelity sampling"). A pure function of a few sums, so that it is tested on its own.

namespace combabc {

// Per candidate (any common scale: the optimum does not depend on it), with w a candidate's
// importance weight and the outcomes those of the next wave's thresholds (the paper's eq. 14):
//  - w: E[w^2 1(expensive accepts)], the paper's W;
//  - w_false_positive: E[w^2 1(cheap accepts, expensive rejects)], W_fp;
//  - w_false_negative: E[w^2 1(cheap rejects, expensive accepts)], W_fn;
//  - cheap_accepted: the fraction of candidates the cheap model accepts, in [0, 1];
//  - cost_ratio: one expensive simulation's cost over one cheap one's, > 0.
struct ContinuationStatistics {
  double w = 0.0;
  double w_false_positive = 0.0;
  double w_false_negative = 0.0;
  double cheap_accepted = 0.0;
  double cost_ratio = 1.0;
};

struct ContinuationProbabilities {
  double continue_if_accepted = 1.0;  // eta_1
  double continue_if_rejected = 1.0;  // eta_2
};

// phi(eta_1, eta_2) = (W - W_fp - W_fn + W_fp / eta_1 + W_fn / eta_2)
//                     * (1 + cost_ratio (eta_1 P_1 + eta_2 (1 - P_1))),
// the expected squared weight times the expected cost of a candidate in units of a cheap
// simulation (the paper's eq. 13): ESS per unit cost is proportional to 1 / phi.
double ContinuationObjective(const ContinuationStatistics& s, double eta_1, double eta_2);

// The minimiser of phi over [floor, 1]^2 (the paper's Proposition 10): the interior stationary
// point (Lemma 8) when it exists and lies in the box, else the best of the four edges' own
// minimisers (Lemma 9). An eta whose error sum is 0 (no false positive, or no false negative)
// goes to the floor; one whose cost term is 0 goes to 1.
ContinuationProbabilities OptimalContinuation(const ContinuationStatistics& s, double floor);

}  // namespace combabc
