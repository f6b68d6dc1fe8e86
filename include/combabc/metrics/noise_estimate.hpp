#pragma once
// Estimates of the measurement noise sigma from the measured points alone (docs/algorithm.md,
// "Noise estimate"), for `sigma_noise = "estimate"` and the fit checks.
#include <cstddef>
#include <span>

namespace combabc {

// Noise standard deviation of y(x) = g(x) + e, e iid N(0, sigma^2), for a g that is smooth except
// at a few points (docs/algorithm.md, "Noise estimate"). Each run of k + 1 = 6 neighbours gives a
// pseudo-residual e_i = sum_j c_j y_{i+j} / |c|, c the fifth divided difference's weights from x
// (c_j = 1 / prod_{m != j} (x_j - x_m)): zero for any quartic g, N(0, sigma^2) for pure noise.
// Where g bends sharply (a steep start, a clamp's kink) e_i holds g's fifth derivative instead, so
// the estimate is robust: s = 1.4826 median |e_i| (the MAD), then the root mean square of the e_i
// with |e_i| <= 3 s, divided by its value for a normal cut at 3 sigma (0.98657); 0 when that is
// at the level of rounding (64 epsilon max |y|). Needs n >= 3 points (with fewer than 6, k = n -
// 1); x strictly increasing.
double EstimateNoiseSigma(std::span<const double> x, std::span<const double> y);

// The variance of a mean square of the N - 5 overlapping fifth differences of N equally spaced
// points is 1 + 2 sum rho^2 = 2.91 times that of N - 5 independent squares (autocorrelations
// -0.83, 0.48, -0.18, 0.04, -0.004): their degrees of freedom are (N - 5) / 2.91.
inline constexpr double kFifthDifferenceOverlap = 2.91;

struct AmplitudeNoiseEstimate {
  double sigma = 0.0;
  // The estimate's effective degrees of freedom (its relative scatter is sqrt(1 / (2 dof))):
  // one per floor point, 1 / 2.91 per pseudo-residual kept.
  double dof = 0.0;
  std::size_t floor_points = 0;      // points read as folded noise, y = |e|
  std::size_t pseudo_residuals = 0;  // fifth differences kept, away from the floor
};

// Noise standard deviation of amplitudes y = |g(x) + e|, e iid N(0, sigma^2), y >= 0
// (docs/algorithm.md, "Noise estimate": amplitude data): a profile at a noise floor (|g| << sigma)
// over some stretches and well above it elsewhere, as a sensor's amplitude away from and near its
// load. Starting from s = EstimateNoiseSigma, repeated until s settles: a point whose neighbours
// (two each side, itself left out) average at most 1.3 s is on the floor, where y = |e| and
// E[y^2] = sigma^2 exactly; the fifth differences e_i of runs of six points off the floor are
// N(0, sigma^2) there, kept when |e_i| <= 3 s;
//   s^2 = (sum_floor y^2 + sum_kept e_i^2 / (2.91 * 0.97334)) / (floor points + kept / 2.91),
// the floor's mean square and the clipped differences' pooled by their degrees of freedom. With
// fewer than 10 points on the floor it is EstimateNoiseSigma. Needs n >= 3 points, x strictly
// increasing, y >= 0. A long stretch whose signal stays within about 2 sigma of zero reads high
// (docs/algorithm.md, "Noise estimate").
AmplitudeNoiseEstimate EstimateAmplitudeNoise(std::span<const double> x, std::span<const double> y);

}  // namespace combabc
