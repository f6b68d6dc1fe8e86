#pragma once
// Which experiment to run next (docs/algorithm.md, "Designing the next experiment"): Bayesian
// experimental design by the expected information gain about the bits (Lindley 1956; with
// simulators: Drovandi & Pettitt 2013, Price et al. 2016, Kleinegesse & Gutmann 2019/2020).
//
// What is known is a weighted population of bit vectors: draws from the prior, a finished run's
// accepted particles with their weights, or, for a space small enough, every configuration with
// its prior mass. For a candidate experiment c each particle's profile Y_ic is simulated once.
// A plausible truth j is drawn from the population, its data are y_jc = Y_{t_j,c} + e with
// e ~ N(0, sigma^2) per point (the noise-aware acceptance at T = 1), and the posterior it would
// give is the population reweighted by the likelihood (importance reweighting):
//   w_i(j) ∝ w_i exp(-|y_jc - Y_ic|^2 / (2 sigma^2)).
// Scores, averaged over the truths (Monte Carlo with a standard error):
//   information gain  H(p) - H(p(j)) in bits, H the sum of the bits' binary entropies of the
//                     marginals p_k = P(bit k = 1) (the marginal entropy: what the clamp figure
//                     shows; the joint entropy of a particle population is not estimable);
//   identified        bits with |p_k(j) - 1/2| > margin (what engineers read: clamps decided);
//   wrong             identified bits on the other side of the truth's bit;
//   identifiability   per bit, E|2 p_k(j) - 1| (0: still the prior's coin, 1: decided).
// Greedy selection: the best candidate, then the one that adds most to it (the truths' data of
// every chosen experiment multiply their likelihoods), and so on.
// Deterministic for a seed whatever the threads: truth j and its noise for candidate c come from
// their own streams.
#include <cstdint>
#include <span>
#include <vector>

namespace combabc::design {

struct DesignOptions {
  double noise_sigma = 0.01;  // per point, in the units of the profiles (normalised: of the peak)
  int truths = 200;           // plausible truths drawn from the population
  int select = 1;             // experiments chosen greedily
  double identified_margin = 0.4;
  std::uint64_t seed = 1;
  int threads = 1;  // 0 = every core
};

struct Population {
  int dimension = 0;
  std::vector<std::uint8_t> bits;  // size() x dimension, row-major
  std::vector<double> weights;     // normalised to sum 1
  std::size_t size() const { return weights.size(); }
};

// Each particle's simulated profile under one candidate: size() x points, row-major, normalised
// as its measured data would be.
struct CandidateProfiles {
  int points = 0;
  std::vector<double> values;
};

struct Score {
  double information_gain = 0.0;  // bits
  double information_gain_se = 0.0;
  double identified = 0.0;  // expected count
  double wrong = 0.0;       // expected count
  // Mean effective sample size (sum w)^2 / sum w^2 of the reweighted population: near 1 the
  // posterior has collapsed onto a few particles, and the gain and the identified count are
  // upper bounds (the population is too small for what the data would tell; docs/algorithm.md).
  double effective_particles = 0.0;
  std::vector<double> identifiability;  // per bit
};

struct DesignResult {
  double prior_entropy = 0.0;  // bits: the population's marginal entropy
  double prior_identified = 0.0;
  std::vector<Score> scores;      // each candidate alone, in candidate order
  std::vector<int> selected;      // the greedy sequence of candidates
  std::vector<Score> cumulative;  // the score of the first 1, 2, ... selected together
};

// The population's marginal P(bit k = 1).
std::vector<double> Marginals(const Population& population);
// sum_k h(p_k) in bits, h(p) = -p log2 p - (1 - p) log2 (1 - p).
double MarginalEntropy(std::span<const double> marginals);

// Throws std::invalid_argument for inconsistent sizes or options.
DesignResult ScoreCandidates(const Population& population,
                             const std::vector<CandidateProfiles>& candidates,
                             const DesignOptions& options);

}  // namespace combabc::design
