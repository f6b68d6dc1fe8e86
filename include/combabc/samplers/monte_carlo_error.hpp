#pragma once
// Monte-Carlo standard errors of a wave's weighted estimates, and the effective sample size of
// each estimated quantity (docs/algorithm.md, "Monte-Carlo errors"). The importance estimator is
// self-normalised, mu = sum w f / sum w: its delta-method variance is
// sum w_i^2 (f_i - mu)^2 / (sum w)^2, which sees how the weights go with f; sd(f) / sqrt(ESS)
// (ESS = 1 / sum w^2 of normalised weights) assumes they do not. The same formula serves the
// paper estimator's equal weights (then it is the textbook sd / sqrt(n)) and a multi-fidelity
// wave's signed weights. A probability's error has a floor, the rule of three
// (WeightedProbability): an estimate of 0 or 1 is not known to be exact.
#include <optional>
#include <span>
#include <vector>

#include "combabc/samplers/run_history.hpp"

namespace combabc {

// A weighted mean with its delta-method standard error and the quantity's own effective sample
// size n_f = Var_w(f) / se^2: the number of independent draws that would give the same standard
// error. For a quantity constant among the particles (no spread to measure it by) se is 0 and
// n_f the weights' ESS, (sum w)^2 / sum w^2.
struct WeightedMoment {
  double value = 0.0;
  double se = 0.0;
  double ess = 0.0;
};

// The mean of `values` under `weights` (one each, of any sign, sum > 0; need not be normalised).
// se is infinite when the weights sum to <= 0 (signed weights that cancel).
// `clusters` (optional, one dense number 0..C-1 per particle): particles that are not independent
// draws, such as a resample-move wave's descendants of one ancestor; their influence terms are
// summed per cluster before squaring (the cluster-robust delta method, Chan & Lai 2013).
WeightedMoment WeightedMean(std::span<const double> weights,
                            std::span<const double> values,
                            std::span<const std::size_t> clusters = {});

// The rule of three: a quantity none of n independent draws showed has probability below 3 / n
// at 95%: (1 - p)^n, the chance that none shows it, is below 0.05 once p > about 3 / n.
inline constexpr double kRuleOfThree = 3.0;

// A probability: the mean of a 0/1 indicator under `weights` (as WeightedMean), clamped to [0, 1]
// (signed weights can put it outside), with a standard error that covers what the delta method
// cannot see:
//   se = max(the delta method's, F - min(p, 1 - p), |raw - p|),  F = min(3 / ESS, 0.5),
// p the clamped estimate. The delta method gives an estimate of 0 or 1 (no particle, or every
// particle, has the quantity) the error 0 and one made of a few particles too small an error;
// the floor makes the interval reach at least F from the nearer edge (0 +- F, 0.01 +- (F - 0.01)),
// and leaves estimates farther than F from both edges alone. ESS: the weights' (sum w)^2 / sum w^2
// (with signed weights Prescott & Baker's, which their cancellation lowers); with
// `heavy_particles` (a multi-fidelity wave) at most sum w / max |w|, the number of heaviest
// particles the total weight is worth: mass that only the expensive model accepts shows up only
// in rare particles continued with a small probability eta and weighted 1 / eta, so three of the
// heaviest could be missing. F is at most 0.5, the largest sd of a probability. ess: the delta
// method's (Var_w / se^2, before the floor).
// With `clusters`, the floor's ESS is that of the clusters' total weights (a cluster counts as one
// draw).
WeightedMoment WeightedProbability(std::span<const double> weights,
                                   std::span<const double> indicator,
                                   bool heavy_particles = false,
                                   std::span<const std::size_t> clusters = {});

// WeightedProbability's two steps, for a probability whose delta-method estimate was computed
// elsewhere (TopConfigurations sums each configuration's weights instead of walking the particles
// once per configuration): the ESS of its floor, and the clamp and floor applied to `m`.
double ProbabilityEss(std::span<const double> weights, bool heavy_particles);
WeightedMoment BoundProbability(WeightedMoment m, double ess);

// The standard deviation sqrt(sum w (f - mu)^2 / sum w) under the same weights, with the
// delta-method standard error of the first two moments: the variance's influence terms are
// (f_i - mu)^2 - var, and se(sd) = se(var) / (2 sd). ess: Var_w((f - mu)^2) / se(var)^2.
WeightedMoment WeightedSd(std::span<const double> weights,
                          std::span<const double> values,
                          std::span<const std::size_t> clusters = {});

// A resample-move wave's clusters for the errors above: particles with one ancestor
// (Particle::ancestor), or with `eve` one Eve (Particle::eve), share a number; empty for a wave
// drawn afresh (independent particles).
std::vector<std::size_t> AncestorClusters(const WaveRecord& wave, bool eve);

// A wave's estimates under its particles' stored weights (the run's estimator): per bit P(bit =
// 1) (WeightedProbability), per real its mean and sd, each with its standard error and effective
// sample size (a resample-move wave's clustered by parent and by Eve: the larger error); a
// multi-fidelity wave's (WaveRecord::multi_fidelity) bits count the rule of three in its heaviest
// particles. `prior_one` (one per bit, or empty): a bit whose prior probability is 0 or 1 has that
// posterior probability exactly, with error 0.
struct WaveErrors {
  std::vector<WeightedMoment> bits;
  std::vector<WeightedMoment> real_means;
  std::vector<WeightedMoment> real_sds;
  // The bits' ESS: the smallest among the bits that vary among the particles (a constant bit has
  // no error to speak of); none when no bit varies or there are no bits.
  std::optional<double> bits_ess;
};
WaveErrors WaveMonteCarloErrors(const WaveRecord& wave, std::span<const double> prior_one = {});

}  // namespace combabc
