#pragma once
// Monte-Carlo standard errors of a wave's weighted estimates, and the effective sample size of
// each estimated quantity (docs/algorithm.md, "Monte-Carlo errors"). The importance estimator is
// self-normalised, mu = sum w f / sum w: its delta-method variance is
// sum w_i^2 (f_i - mu)^2 / (sum w)^2, which sees how the weights go with f; sd(f) / sqrt(ESS)
// (ESS = 1 / sum w^2 of normalised weights) assumes they do not. The same formula serves the
// paper estimator's equal weights (then it is the textbook sd / sqrt(n)) and a multi-fidelity
// wave's signed weights.
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
WeightedMoment WeightedMean(std::span<const double> weights, std::span<const double> values);

// The standard deviation sqrt(sum w (f - mu)^2 / sum w) under the same weights, with the
// delta-method standard error of the first two moments: the variance's influence terms are
// (f_i - mu)^2 - var, and se(sd) = se(var) / (2 sd). ess: Var_w((f - mu)^2) / se(var)^2.
WeightedMoment WeightedSd(std::span<const double> weights, std::span<const double> values);

// A wave's estimates under its particles' stored weights (the run's estimator): per bit P(bit =
// 1), per real its mean and sd, each with its standard error and effective sample size.
struct WaveErrors {
  std::vector<WeightedMoment> bits;
  std::vector<WeightedMoment> real_means;
  std::vector<WeightedMoment> real_sds;
  // The bits' ESS: the smallest among the bits that vary among the particles (a constant bit has
  // no error to speak of); none when no bit varies or there are no bits.
  std::optional<double> bits_ess;
};
WaveErrors WaveMonteCarloErrors(const WaveRecord& wave);

}  // namespace combabc
