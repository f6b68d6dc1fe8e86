#pragma once
// The correlated binary kernel: logistic conditionals (Schäfer & Chopin 2013, "Sequential Monte
// Carlo on large binary sampling spaces", Statistics and Computing 23:163-184),
//   q(x) = prod_i q(x_i | x_<i),   q(x_i = 1 | x_<i) = sigmoid(b_i0 + sum_{k in S_i} b_ik x_k),
// fitted to the previous wave's weighted population. Unlike the independent kernel it can follow a
// posterior whose mass sits on a few correlated configurations. Its density is exact (a product of
// normalised conditionals), so importance weights stay exact. See docs/algorithm.md.
//
// Fit, in order:
//  1. identical rows are collapsed (weights summed) and zero-weight rows dropped;
//  2. weighted marginals m_i; a bit with min(m_i, 1 - m_i) < min_marginal is proposed from its
//     marginal alone and is never a predecessor;
//  3. S_i = the predecessors k < i with |weighted correlation(x_i, x_k)| > min_correlation, the
//     max_predecessors largest kept (Schäfer & Chopin's sparse version);
//  4. b_i by weighted Newton-Raphson on the log-likelihood with a ridge on the slopes, started at
//     the marginal's logit; a fit that does not converge (50 iterations) falls back to the
//     marginal;
//  5. every conditional is clipped to [clip, 1 - clip], so every configuration has q > 0.
// A bit with s <= 10 predecessors is regressed on the at most 2^s patterns of its predecessors
// (rows merged, the same likelihood), and its tempered conditional is tabulated per pattern
// (P(x_i = 1) and both log q values), so that sampling and the density cost a lookup per bit.
//
// Tempering toward the prior p (Eq. 3 of the paper, generalised to conditionals):
//  - kGeometric: each conditional is tempered by TemperedProbability(q_i(x_<i), prior_i, phi),
//    i.e. logit q_i = (1 - phi) logit q_fit,i + phi logit prior_i. For independent bits this is
//    Eq. 3 itself; for conditionals it is again a product of normalised conditionals, so the
//    density stays exact (it is not the normalised joint q_fit^(1-phi) p^phi, which has no closed
//    form).
//  - kMixture: q = (1 - phi) q_fit + phi p as a joint mixture.
// phi = 0 gives q_fit and phi = 1 the prior, whatever the form. An empty population or one of zero
// total weight gives the prior too.
//
// Random draws, in order (Sample uses only the stream it is given): kMixture with 0 < phi < 1
// first draws u = Uniform() and proposes from the prior when u < phi; then one Uniform() per free
// bit, i = 0 .. f - 1, with x_i = 1 when it is below P(x_i = 1 | x_<i).
//
// Marginals(): exact for bits without predecessors; for the others the average of P(x_j = 1 | x_<j)
// over 1024 forward draws, draw k from RandomStream(0x1061571c, 0, k) (the same on every run).
#include <memory>

#include "combabc/proposals/proposal.hpp"
#include "combabc/proposals/proposal_options.hpp"

namespace combabc {

// Throws combabc::Error(kConfig) with LogisticKernelOptions::IsValid's message if `options` is not
// valid.
std::unique_ptr<BinaryKernel> MakeLogisticKernel(const LogisticKernelOptions& options);

}  // namespace combabc
