#pragma once
// Gaussian kernels' covariance factors and constants, shared by the continuous kernels and the
// ancestor kernel.
#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "combabc/params/parameter_space.hpp"

namespace combabc {

constexpr double kLogRootTwoPi = 0.91893853320467274178;  // log sqrt(2 pi)
// A Gaussian kernel's Sample gives up after this many draws in a row outside the prior's support
// (proposal.hpp).
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

}  // namespace combabc
