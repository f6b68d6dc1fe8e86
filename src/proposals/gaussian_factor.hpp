#pragma once
// Gaussian kernels' covariance factors and constants, shared by the continuous kernels and the
// ancestor kernel.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "combabc/params/parameter_space.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

constexpr double kLogRootTwoPi = 0.91893853320467274178;  // log sqrt(2 pi)
// A Gaussian kernel's Sample gives up after this many draws in a row outside the prior's support
// (proposal.hpp). A kernel that truncates each coordinate (TruncateEachCoordinate) draws inside
// every real's bounds, so only a joint prior's constraint between its reals can reject a draw.
constexpr int kMaxSupportTries = 10000;

// Index of element (i, k), k <= i, of a lower-triangular matrix stored row by row.
constexpr std::size_t Tri(std::size_t i, std::size_t k) { return i * (i + 1) / 2 + k; }

// A Gaussian's factor Sigma = L L^T: L and L^{-1} (both lower triangular, packed with Tri) and
// log det L = sum log L_ii.
struct Factor {
  std::vector<double> l, l_inv;
  double log_det = 0.0;
};

// Sigma's factor, regularised in units of each real's prior standard deviation `prior_sd`
// (gaussian_factor.cpp says how): always positive definite.
Factor Factorise(Eigen::MatrixXd sigma, const std::vector<double>& prior_sd);

// Each real's prior standard deviation (finite for every valid prior).
std::vector<double> PriorSd(const ParameterSpace& space);

// Each real's support as an interval [low, high] (either end may be infinite): what a Gaussian
// kernel truncates its components to, coordinate by coordinate.
struct Box {
  std::vector<double> low, high;
  std::vector<std::uint8_t> bounded;      // 1 where an end is finite
  std::vector<ContinuousPrior> marginal;  // for each real's own InSupport (open ends, rounding)
};
Box SupportBox(const RealsPrior& prior);

// r = c + L z, z ~ N(0, 1)^d: one draw of the untruncated Gaussian N(c, L L^T).
void SampleGaussian(const Factor& f, const double* c, RandomStream& rng, std::span<double> r);

// Whether a mixture of Gaussians sum_j w_j N(c_j, Sigma_j) (component j by the running sums of
// the weights `cumulative`, its factor by factor_of(j), its centre at centres + j d) must be
// truncated coordinate by coordinate (SampleInBox, LogBoxMass) rather than redrawn whole until
// inside the box: when under kMinInsideFraction of 2000 draws of a fixed stream land inside. Both
// are exact (a whole redraw's constant is common to the wave and cancels in self-normalised
// weights); redrawing keeps the density O(N d) per candidate, where truncation costs a log-mass
// per bounded coordinate and component, so it is kept for kernels that would rarely land inside
// (many bounded reals: a 20-real box holds ~1e-5 of wave 1's kernel).
bool TruncateEachCoordinate(const std::vector<double>& cumulative,
                            const std::vector<double>& centres,
                            const std::function<const Factor&(std::size_t)>& factor_of,
                            const Box& box);

// One draw of the Gaussian N(c, L L^T) restricted to the box, without rejection: coordinate by
// coordinate, z_i ~ N(0, 1) truncated to the interval that keeps r_i = c_i + sum_{k<=i} L_ik z_k
// inside [low_i, high_i] given z_0..z_{i-1} (the Geweke-Hajivassiliou-Keane construction).
// Its density on the box is N(r; c, L L^T) / prod_i P_i(r), P_i the N(0, 1) mass of coordinate i's
// interval: exactly normalised, and what LogBoxMass gives the log of the product of. An unbounded
// coordinate takes a plain rng.Normal(), as an untruncated Gaussian would. `z` is d scratch.
void SampleInBox(const Factor& f,
                 const double* c,
                 const Box& box,
                 RandomStream& rng,
                 std::span<double> r,
                 std::span<double> z);

// sum_i log P_i(r) for the draw r of SampleInBox whose whitened offset L^{-1} (r - c) is
// y - w (w may be null: zero), so that a caller with whitened centres precomputed pays O(1) per
// coordinate, and nothing for a coordinate that is unbounded or whose interval lies beyond
// kFarSd on both sides (its P_i differs from 1 by under 2e-17).
double LogBoxMass(
    const Factor& f, const Box& box, std::span<const double> r, const double* y, const double* w);

}  // namespace combabc
