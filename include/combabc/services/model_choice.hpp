#pragma once
// ABC model choice (docs/algorithm.md, "Model choice"): the posterior probability of each of
// several candidate models, P(M_k | D) = pi_k Z_k / sum_j pi_j Z_j, from each model's own run
// (Didelot, Everitt, Johansen & Lawson 2011, Bayesian Analysis 6:49): Z_k is the model's ABC
// evidence E_prior[P(accept | theta)] at the common final thresholds, estimated from the run's
// waves, or computed exactly by enumeration.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc {

// One model's ABC evidence, in logs (a likelihood component's evidence, prod_k exp(-d_k), may
// underflow a double).
struct ModelEvidence {
  std::string name;
  double prior = 0.0;  // the model's prior probability pi_k
  // log Z at the final thresholds: -inf when no particle reached them (see upper).
  double log_evidence = -std::numeric_limits<double>::infinity();
  double relative_se = 0.0;  // the Monte-Carlo standard error of Z over Z (0 when exact)
  // log of a 95 % upper bound of Z: the estimate + 2 se, or where no particle reached the final
  // thresholds the rule of three (3 / the wave's candidates for the prior's wave 0; the evidence at
  // the last wave's own, wider thresholds + 2 se otherwise: Z can only fall as they tighten).
  double log_upper = -std::numeric_limits<double>::infinity();
  bool reached = false;          // estimated at the final thresholds (else an upper bound only)
  bool exact = false;            // by enumeration
  int wave = -1;                 // the wave it was estimated from (-1: none)
  std::int64_t simulations = 0;  // the run's simulations, all waves
  std::string termination;       // the run's, for the report ("" for an enumeration)
  // Per wave t of the run: log Z at wave t's own thresholds (NaN where the wave gives no
  // estimate: a resample-move run's wave 0, an incomplete wave) and its relative standard error;
  // ModelProbabilitiesByWave's input (empty for an enumeration).
  std::vector<double> wave_log_evidence;
  std::vector<double> wave_relative_se;
};

// The evidence of a run's history at `final_thresholds` (one per threshold or likelihood slot:
// a likelihood component's temperature, 1 for the error model's own likelihood).
//  - A rejection wave (proposal q, weights w = p / q as stored, accepted with probability
//    a(d) = min(1, exp(-sum (d - m) / T)) with the sampler's offsets m): each accepted particle
//    carries y = w L / a, L the likelihood at the wave's thresholds without offsets, whose mean
//    over all candidates is unbiased for Z (Horvitz-Thompson). A complete wave stops at its n-th
//    acceptance (inverse sampling): Z = (n - 1) / (N - 1) x mean(y over the accepted), unbiased,
//    with relative variance (1 - p) / n + var(y) / (n mean(y)^2).
//  - A resample-move wave: Z_t = Z_{t-1} x sum_i W_i A_t(d_i) / A_{t-1}(d_i) over the previous
//    wave's weighted particles (Del Moral, Doucet & Jasra 2006), the relative variances of the
//    factors added (each factor's from the cluster-robust delta method; waves taken as
//    independent, an approximation). A rejection wave after the first with reals too: its
//    proposal's density omits the mass of the reals' support (draws outside are drawn again),
//    which would scale the estimate above by a constant, but not the self-normalised W_i.
// The estimate is taken at the last complete wave whose thresholds are the final ones; a run that
// never got there gives its upper bound only. `components` are the distance's, in order.
// Refused (Error kUsage): a multi-fidelity history (signed weights of two simulators).
ModelEvidence EstimateEvidence(const RunHistory& history,
                               std::span<const DistanceComponent> components,
                               const std::vector<double>& final_thresholds);

// A model's posterior probability with its delta-method standard error (independent runs):
// Var P_k = P_k^2 [(1 - P_k)^2 r_k^2 + sum_{j != k} P_j^2 r_j^2], r the relative errors.
// A model without an estimate (reached = false) is given its upper bound: the probability it
// would have at its evidence's upper bound, the others' estimates unchanged (upper_bound_only);
// the others' probabilities are computed with its evidence 0.
struct ModelProbability {
  std::string name;
  double prior = 0.0;
  double probability = 0.0;  // NaN when no model reached the final thresholds
  double se = 0.0;
  bool upper_bound_only = false;
  double upper = 1.0;  // upper_bound_only: P(M_k | D) is below this (95 %)
};
std::vector<ModelProbability> ModelProbabilities(std::span<const ModelEvidence> models);

// The model probabilities after each wave t = 0, 1, ... of the longest run (model_choice/
// waves.csv and its figure): each model's evidence at its own wave-t thresholds (its last wave's
// once its run has ended) combined as ModelProbabilities does; a model without an estimate at
// wave t is given Z <= 1 (nothing known) as its upper bound. Each run adapts its own thresholds,
// so before the common final ones the models' evidences are at different epsilons (or
// temperatures): the rows show how the probabilities settled, not probabilities at one epsilon.
std::vector<std::vector<ModelProbability>> ModelProbabilitiesByWave(
    std::span<const ModelEvidence> models);

}  // namespace combabc
