#pragma once
// The continuous proposal kernels: Gaussian mixtures centred on the previous wave's particles,
// q(r) = sum_j w_j N(r; r_j, Sigma_j), truncated to the prior's support (Sample draws again until
// it lands inside; LogDensity omits the truncation constant, which is common to the wave).
#include <memory>

#include "combabc/proposals/proposal.hpp"

namespace combabc {

// Sigma_j = scale x the population's weighted covariance, the same for every particle (Beaumont,
// Cornuet, Marin & Robert 2009, Biometrika 96:983, who take scale = 2 from a Kullback-Leibler
// argument; Toni et al. 2009). Throws combabc::Error(kConfig) unless scale is finite and
// > 0.
std::unique_ptr<ContinuousKernel> MakeNormalKernel(double scale);

// Sigma_j = sum_k w~_k (r_k - r_j)(r_k - r_j)^T over the particles k that also satisfy the next
// wave's thresholds, w~ their weights renormalised (the optimal local covariance matrix, OLCM, of
// Filippi, Barnes, Cornebise & Stumpf 2013, SAGMB 12:87); all particles when none do.
std::unique_ptr<ContinuousKernel> MakeOlcmKernel();

}  // namespace combabc
