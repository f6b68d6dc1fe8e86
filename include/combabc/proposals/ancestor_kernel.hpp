#pragma once
// The ancestor kernel: one joint proposal over the free bits and the reals, for mixed spaces where
// a product q(bits) q(reals) draws reals without regard to the bits they go with
// (docs/algorithm.md, "Proposal kernels"). Each candidate descends from an ancestor particle j of
// the previous wave, drawn with probability w_j:
//   q(b, r) = (1 - a) sum_j w_j F(b | b_j) N(r; r_j, Sigma_g(j)) + a p(b) p(r),
// truncated to the prior's support of the reals (the whole draw repeated; the constant is common
// to the wave). Here
//  - F(b | b_j) = prod_i e_i^[b_i != b_ji] (1 - e_i)^[b_i == b_ji]: each free bit of the ancestor
//    flipped on its own with rate e_i = clamp(min(m_i, 1 - m_i), 0.1 / f, 0.5), m_i the weighted
//    marginal of bit i (a bit the population agrees on is kept, one it splits on is redrawn), and
//    at least 0.1 / f so that about one candidate in ten moves a bit the population holds fixed;
//  - Sigma_g = scale x the weighted covariance of the reals among the particles with the
//    ancestor's bit pattern g (a pattern's own scale: a minor mode that needs other reals keeps
//    them), or scale x the whole population's weighted covariance when the pattern's particles
//    have an effective sample size below 10 (too few for a covariance);
//  - a = max(0.05, phi): a defensive mixture with the prior (Hesterberg 1995), so that every
//    configuration keeps support, and the wave's tempering phi toward the prior as a mixture
//    (whatever [sampler.tempering] form says).
// LogDensity sums over ancestors grouped by distinct bit pattern: O(G f + N r^2) per candidate
// for G patterns among N particles, f free bits, r reals. LogBitsDensity is the bits' marginal
// before the truncation of the reals (exact when the Gaussians put all their mass inside the
// support, as with unbounded priors).
//
// Random draws, in order (Sample uses only the stream it is given): u = Uniform(), the prior when
// u < a (its bits, then each real from its prior); else the ancestor (Uniform()), one Bernoulli
// per free bit (the flips), one Normal() per real; repeated whole while the reals fall outside the
// support.
#include <memory>

#include "combabc/proposals/proposal.hpp"

namespace combabc {

// Throws combabc::Error(kConfig) unless scale is finite and > 0.
std::unique_ptr<JointKernel> MakeAncestorKernel(double scale);

}  // namespace combabc
