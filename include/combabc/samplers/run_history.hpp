#pragma once
// What a run produces: one record per wave with its statistics and accepted particles.
// Everything except wall times is a deterministic function of (options, seed): that is the
// determinism and resume contract (see SameHistory).
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"

#include "combabc/params/parameter_value.hpp"
#include "combabc/samplers/simulator.hpp"
#include "combabc/samplers/smc_options.hpp"

namespace combabc {

struct Particle {
  std::int64_t index = 0;   // candidate index within its wave
  ParameterValue theta;     // full bit vector (0/1) and the reals
  double log_weight = 0.0;  // log p(theta)/q(theta), unnormalised
  double weight = 0.0;      // normalised weight under the run's estimator (may be < 0)
  // Multi-fidelity runs only (SmcProblem::low_fidelity); else 1, empty and false.
  //  - multiplier: MultiFidelityMultiplier of the candidate; the weight is proportional to it.
  //  - low_distance: the cheap simulator's distance, one value per component.
  //  - confirmed: the expensive simulator ran, so `distance` and `output` are its own (else they
  //    are the cheap simulator's).
  double multiplier = 1.0;
  std::vector<double> low_distance;
  bool confirmed = false;
  std::vector<double> distance;  // one value per distance component
  std::vector<double> output;    // simulated Y* (empty unless SmcOptions::keep_outputs)
  // A resample-move wave's particle: the index (Particle::index) of the previous wave's particle
  // it was resampled from and then moved. -1 for a particle drawn afresh.
  std::int64_t ancestor = -1;
  // Derived, not stored (AssignEveIndices): the index of the particle it descends from in the
  // last wave drawn afresh (Chan & Lai 2013's Eve index). Particles of one parent or of one Eve
  // are correlated; the Monte-Carlo errors count each group as one cluster.
  std::int64_t eve = -1;
};

// A candidate whose simulation failed (SimulationFailed, or an output or distance holding NaN):
// never accepted, counted as simulated.
struct SimulationFailure {
  std::int64_t index = 0;  // candidate index within its wave
  std::string reason;      // at most kFailureReasonBytes - 1 bytes
  bool operator==(const SimulationFailure&) const = default;
};

// A multi-fidelity wave's continuation probabilities and costs (docs/algorithm.md,
// "Multi-fidelity sampling").
struct WaveFidelity {
  double continue_if_accepted = 1.0;  // eta_1 this wave used
  double continue_if_rejected = 1.0;  // eta_2 this wave used
  // Expensive simulations among the wave's `candidates` (each of which ran the cheap simulator).
  std::int64_t expensive_simulations = 0;
  // Wall time of the cheap and expensive simulator calls, summed over the wave's candidates (a
  // batch call's time shared equally among its candidates); not deterministic, excluded from
  // SameHistory.
  double cheap_seconds = 0.0;
  double expensive_seconds = 0.0;
  // The false positives (the cheap simulator accepts, the expensive one rejects) among the
  // wave's candidates that are not particles because their multiplier is 0 (eta_1 = 1): how many,
  // and log sum exp(2 log_weight) over them (-inf for none). The tuning of the next wave's eta_1
  // needs them, and a resumed wave must see the same.
  std::int64_t unkept_false_positives = 0;
  double unkept_false_positive_log_w2 = -std::numeric_limits<double>::infinity();
  // Set when the wave ends (complete): the continuation probabilities tuned for the next wave
  // (MultiFidelityOptions::adapt; else the fixed ones) and the expensive-to-cheap cost ratio the
  // tuning assumed. Stored with this wave so that a run resumed between waves goes on with them.
  double next_continue_if_accepted = 1.0;
  double next_continue_if_rejected = 1.0;
  double cost_ratio = 0.0;
};

// What the Metropolis-Hastings steps of a resample-move wave did (docs/algorithm.md,
// "Resample-move"). Its particles are the previous wave's, reweighted to the wave's target,
// resampled and moved; the wave's `candidates` are the proposals (one simulation each) and its
// acceptance rate their acceptance.
struct WaveMoves {
  // The effective sample size of the previous wave's particles reweighted to this wave's target,
  // before resampling.
  double survivor_ess = 0.0;
  // The fraction of the schedule's step (in threshold quantile or inverse temperature) this wave
  // took, 1 unless shortened to keep MoveOptions::ess_fraction of the ESS.
  double step = 1.0;
  int rounds = 0;                         // every particle took this many proposals
  std::int64_t proposed = 0;              // proposals, all rounds (= simulations)
  std::int64_t accepted = 0;              // accepted proposals
  std::int64_t independent_proposed = 0;  // of the proposals: from the fitted kernel
  std::int64_t independent_accepted = 0;  // and accepted
  bool operator==(const WaveMoves&) const = default;
};

// A PatternClass's bit that the class leaves free (a class of one or two bits' values).
inline constexpr std::uint8_t kAnyBit = 2;

// One pattern class of the population a wave's proposal was fitted to: its particles that share
// a bit configuration, or one or two bits' values (docs/algorithm.md, "Mode loss"). A wave records
// the heavy whole patterns and the flagged classes of one or two bits' values
// (FindPatternClasses), each with the share of the wave's particles its proposal is expected to
// give it, flagged when that is so small that the class may be lost.
struct PatternClass {
  std::vector<std::uint8_t> bits;  // the full bit vector: 0/1, kAnyBit where the class is free
  double mass = 0.0;               // the population's normalised weight of the class
  double proposal = 0.0;           // the expected share of the wave's accepted particles
  bool flagged = false;            // proposed with negligible probability (mode loss)
  bool operator==(const PatternClass&) const = default;
};

struct WaveRecord {
  int wave = 0;
  std::vector<double> thresholds;  // eps_t per threshold component
  double phi = 0.0;                // tempering phi(t) used by this wave's proposal
  std::vector<double> proposal;    // P(free bit = 1) under this wave's binary proposal
  std::int64_t candidates = 0;     // candidates simulated (consumed) in this wave
  std::int64_t accepted = 0;
  double acceptance_rate = 0.0;
  bool complete = false;                     // reached accepted_per_wave
  std::vector<double> marginals_paper;       // per bit: unweighted fraction of 1s (Eq. 2)
  std::vector<double> marginals_importance;  // per bit: p/q-weighted fraction of 1s
  double ess = 0.0;                          // effective sample size of the importance weights
  std::vector<double> reals_mean;            // per real: mean under the estimator's weights
  std::vector<double> reals_sd;              // per real: standard deviation, likewise
  std::int64_t distinct = 0;                 // distinct accepted bit configurations
  // Pearson correlation of bits i and j under the particles' weights (PairCorrelations),
  // row-major d x d; 0 for a bit constant among the particles. Empty without particles, and
  // beyond kMaxPairCorrelationBits bits.
  std::vector<double> pair_correlations;
  std::int64_t discarded = 0;  // simulated past the last acceptance (parallel overshoot)
  // The failed simulations among `candidates`, in candidate order.
  std::vector<SimulationFailure> failures;
  double wall_seconds = 0.0;                   // not deterministic; excluded from SameHistory
  std::optional<WaveFidelity> multi_fidelity;  // set in a multi-fidelity run only
  std::optional<WaveMoves> moves;              // set for a resample-move wave only
  // The previous wave's heavy pattern classes under this wave's proposal (FindPatternClasses), set
  // when the wave starts; none in wave 0, which proposes from the prior.
  std::vector<PatternClass> pattern_classes;
  std::vector<Particle> particles;

  // The estimator's marginals (what the run reports and proposes from).
  const std::vector<double>& marginals(Estimator estimator) const {
    return estimator == Estimator::kPaper ? marginals_paper : marginals_importance;
  }
};

enum class Termination {
  kTargetReached,         // the final threshold of every component was reached
  kMaxWaves,              // num_waves completed (adaptive thresholds above target)
  kBudgetExhausted,       // max_simulations reached
  kAcceptanceRateTooLow,  // a wave fell below min_acceptance_rate
  kWallTimeExceeded,      // max_wall_time_s reached
  kInterrupted,           // the observer asked to stop
  kEnumerated,            // exact enumeration (Enumerate): one wave holding the exact posterior
  kTooManyFailures,       // more than max_failure_fraction of the simulations failed
  // A multi-fidelity wave kept kMultiFidelityParticlesPerAccepted x n_t particles whose signed
  // weights still count fewer than n_t effective ones (final: the options that decide it are
  // part of the run's fingerprint).
  kTooManyParticles,
};
template <>
struct EnumNames<Termination> {
  static constexpr std::pair<Termination, const char*> kNames[] = {
      {Termination::kTargetReached, "target_reached"},
      {Termination::kMaxWaves, "max_waves"},
      {Termination::kBudgetExhausted, "budget_exhausted"},
      {Termination::kAcceptanceRateTooLow, "acceptance_rate_too_low"},
      {Termination::kWallTimeExceeded, "wall_time_exceeded"},
      {Termination::kInterrupted, "interrupted"},
      {Termination::kEnumerated, "enumerated"},
      {Termination::kTooManyFailures, "too_many_failures"},
      {Termination::kTooManyParticles, "too_many_particles"},
  };
};

struct RunSummary {
  Termination termination = Termination::kMaxWaves;
  std::string message;
  int waves_completed = 0;
  std::int64_t simulations = 0;  // candidates consumed, all waves
  std::int64_t simulations_discarded =
      0;                      // simulated past a wave's last acceptance (parallel overshoot)
  std::int64_t failures = 0;  // failed simulations among `simulations`, all waves
  double wall_seconds = 0.0;
  std::string BriefReport() const;
};

struct RunHistory {
  std::vector<WaveRecord> waves;  // completed waves, then at most one incomplete last wave
  RunSummary summary;
  std::string FullReport(Estimator estimator) const;
};

// A pattern as the answer prints configurations, "0110...", bit 1 first, '-' for a kAnyBit; beyond
// 64 bits the first 64 and how many of all are set, or for a class of a few bits' values those
// values ("bit 70 = 1, bit 72 = 0").
std::string PatternText(const std::vector<std::uint8_t>& bits);

// The mode-loss warning of a wave with flagged pattern classes, one line without a newline: "wave
// 3 proposed pattern 0001 (mass 0.076) with probability 2.1e-06; the posterior may have lost a
// mode" (waves counted from 1, the heaviest flagged class named, any others counted). Empty when
// none is flagged.
std::string ModeLossWarning(const WaveRecord& wave);

// Weighted sums over a population of bit vectors, from which its marginals and the Pearson
// correlation of every pair of bits follow (docs/algorithm.md, "Pair correlations"): the one
// estimator of both, for Enumerate (every accepted configuration, weighted by its prior mass) and
// for a wave (its particles, weighted as the run's estimator weighs them). Sums run in the order
// of Add, so a population added in the same order gives the same bits.
class BitMoments {
 public:
  explicit BitMoments(std::size_t bits);
  void Add(std::span<const std::uint8_t> bits, double weight);
  double total() const { return total_; }  // the sum of the weights
  // Multiplies every weight added so far by `factor` (> 0): a running sum of exp(log w) rescaled
  // when a larger log w arrives, so that none underflows.
  void Scale(double factor);
  // P(bit k = 1): the weight of the members with bit k set over total() (> 0).
  std::vector<double> Marginals() const;
  // Pearson correlation of bits i and j, row-major d x d. A bit constant in the population (its
  // sum is 0 or total()) has no correlation: reported as 0, diagonal included, so that the matrix
  // never holds NaN.
  std::vector<double> Correlations() const;

 private:
  std::size_t d_;
  double total_ = 0.0;
  std::vector<double> ones_;      // per bit: the weight of the members with it set
  std::vector<double> pairs_;     // at i * d + j, i < j: the weight of those with both set
  std::vector<std::size_t> set_;  // the set bits of the member being added
};

// The most bits whose pair correlations each wave keeps: the matrix costs N d^2 / 2 operations
// and 8 d^2 bytes per wave (256 bits: 0.5 MiB), which at the 4096-bit limit would be 134 MB per
// wave and dominate the run. Beyond it, pair correlations come from the particles on request
// (export's particles.csv, Python's History.particles).
constexpr std::size_t kMaxPairCorrelationBits = 256;

// WaveRecord::pair_correlations: BitMoments over the particles in order, with their weights
// (empty without particles or with more than kMaxPairCorrelationBits bits).
std::vector<double> PairCorrelations(const std::vector<Particle>& particles);

// Per-bit marginals, pair correlations, the reals' means and standard deviations, ESS and
// distinct count recomputed from a wave's particles (also used by the storage layer when
// reloading a run).
void ComputeWaveStatistics(WaveRecord& wave, Estimator estimator);

// Sets Particle::eve of every resample-move wave's particles from their ancestors, wave by wave:
// the ancestor's own Eve when the previous wave was a move wave, else the ancestor's index. What
// a loaded history needs before its errors (WaveMonteCarloErrors) are computed.
void AssignEveIndices(std::vector<WaveRecord>& waves);

// True when the two histories agree in everything deterministic (all but wall times). On a
// difference, *where says what differs first.
bool SameHistory(const RunHistory& a, const RunHistory& b, std::string* where);

}  // namespace combabc
