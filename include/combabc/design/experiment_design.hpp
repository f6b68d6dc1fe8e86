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
  // Per bit, E[|Y(truth) - Y(truth, bit flipped)|^2 / (2 sigma^2)] over this candidate's scan:
  // the expected log-likelihood ratio its data give against flipping the bit alone (what
  // "below the noise" means: near 0). NaN where the flips are not in the population.
  std::vector<double> flip_signal;
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

// Truths drawn by weight (inverse CDF of one uniform each, from (seed, truth stream, j)): the
// population indices ScoreCandidates uses.
std::vector<std::size_t> DrawTruths(std::span<const double> weights,
                                    int truths,
                                    std::uint64_t seed);

// Throws std::invalid_argument for inconsistent sizes or options.
DesignResult ScoreCandidates(const Population& population,
                             const std::vector<CandidateProfiles>& candidates,
                             const DesignOptions& options);

// The local posterior around each truth (docs/algorithm.md, "Honest predictions"). A finished
// run's particles are too few to stand for the posterior a new experiment would leave: reweighted,
// they collapse onto a handful, and every clamp looks decided. Around each truth drawn from them
// instead: the truth, its one-bit neighbours (each free parameter flipped), the swaps of
// confusable pairs (a fixed clamp and its free mirror or neighbour exchanged) and its mirror image
// across the centreline (Neighbourhood::groups), each weighted by its
// prior times the run's own likelihood of the data measured so far. Clamp k's P(truth's value) is
// the smallest of its two-state posterior (truth against the flip), the four-state posteriors of
// its pairs and the two-state posteriors against the groups that flip it, given the new data; the
// scores follow from those marginals as in ScoreCandidates.
struct Neighbourhood {
  std::vector<int> rows;    // rows of LocalPopulation; rows[0] is the truth's configuration
  std::vector<int> single;  // per free parameter: its flip's position in rows, -1 when it cannot
  struct Swap {
    int first = 0, second = 0;  // free parameters
    int position = 0;           // in rows: both flipped
  };
  std::vector<Swap> swaps;
  // Moves of several free parameters at once (the mirror image across the centreline, which a
  // centreline load and scan cannot tell from the truth): each parameter it flips is also judged
  // against the move alone.
  struct Group {
    std::vector<int> flipped;  // free parameters
    int position = 0;          // in rows
  };
  std::vector<Group> groups;
};

struct LocalPopulation {
  int dimension = 0;               // bits
  std::vector<int> free_of_bit;    // per bit, the free parameter that drives it
  std::vector<std::uint8_t> bits;  // rows x dimension
  std::vector<double> log_weight;  // per row: log prior + log likelihood of the data so far
  std::vector<Neighbourhood> truths;
  std::size_t rows() const { return log_weight.size(); }
};

// Per free parameter, its P(the truth's value) in one neighbourhood given each row's log weight
// (lw[p] for nb.rows[p]): the least of its two-state posterior against its flip, the four-state
// posteriors of its pairs and the two-state posteriors against the groups that flip it (the most
// confusable alternative). 1 where no alternative is in the neighbourhood. Throws
// std::invalid_argument unless lw has one entry per row.
std::vector<double> ProbabilityOfTruth(const Neighbourhood& nb, std::span<const double> lw);

// As ScoreCandidates, over the neighbourhoods (candidates' profiles: rows() x points); the
// number of truths is truths.size(). prior_entropy and prior_identified are the neighbourhoods'
// before any new data, from which the gains count.
DesignResult ScoreNeighbourhoods(const LocalPopulation& population,
                                 const std::vector<CandidateProfiles>& candidates,
                                 const DesignOptions& options);

}  // namespace combabc::design
