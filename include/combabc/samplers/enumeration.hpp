#pragma once
// Exact ABC by enumeration: every configuration of the free bits is simulated once, so the ABC
// posterior p(theta | d(theta) <= eps) ∝ prior(theta) 1[accepted] (times exp(-d / T) for a
// noise-aware likelihood component) is computed exactly instead of estimated. Feasible while 2^free
// bits stays small (kMaxEnumerationBits); the reference an SMC run can be checked against
// (docs/algorithm.md, "Exact enumeration").
#include <cstdint>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc {

// 2^24 configurations: about 17 million simulations, hours for the sensor model; beyond that
// enumeration stops being a check one waits for.
inline constexpr int kMaxEnumerationBits = 24;

struct EnumerationOptions {
  // One per threshold or likelihood component of the distance, in component order: a threshold,
  // or a likelihood component's temperature T, whose configurations then weigh
  // prior x exp(-d / T) (indicator components must equal their required value, as in the
  // sampler).
  std::vector<double> thresholds;
  int threads = 1;             // ThreadPoolExecutor threads when SmcProblem::executor is null
  int batch_size = 4096;       // configurations per Execute (and per ShouldStop / OnBatch)
  int max_particles = 100000;  // accepted configurations kept as particles (by mass)
  int top = 20;                // configurations listed in EnumerationResult::top
  bool keep_outputs = true;    // keep each kept particle's simulated output
  std::uint64_t seed = 1;      // configuration i simulates with RandomStream(seed, 0, i)
};

struct EnumerationResult {
  std::int64_t configurations = 0;  // 2^free bits
  std::int64_t enumerated = 0;      // < configurations only when interrupted
  std::int64_t accepted = 0;        // accepted configurations (of prior mass > 0)
  bool interrupted = false;
  double evidence = 0.0;  // prior mass of the accepted configurations, P(accepted)
  // The exact ABC posterior (empty when nothing was accepted).
  std::vector<double> marginals;  // per bit: P(bit = 1 | accepted)
  // Pearson correlation of bits i and j under the posterior, row-major d x d. A bit that is
  // constant under the posterior has no correlation; it is reported as 0 (also on the diagonal)
  // so that the matrix never holds NaN.
  std::vector<double> correlations;
  double ess = 0.0;  // 1 / sum of squared normalised masses: the effective number of configurations
  // The `max_particles` accepted configurations of largest mass (ties: smaller index first), in
  // configuration order. index = configuration number (free bit j = bit j of the index);
  // log_weight = log prior (+ the likelihood components' -d / T); weight = mass normalised over
  // the kept particles.
  std::vector<Particle> particles;
  // The `top` configurations of largest mass, largest first; weight = mass / evidence.
  std::vector<Particle> top;
  double wall_seconds = 0.0;

  // The run as one wave (wave 0) in the history's format: candidates = configurations enumerated,
  // accepted = accepted configurations, both marginals the exact ones, particles as above.
  WaveRecord Wave(const std::vector<double>& thresholds, const std::vector<double>& proposal) const;
};

// Enumerates every free-bit configuration of problem.space (purely binary, at most
// kMaxEnumerationBits free bits; otherwise Error kConfig). Sums run in configuration order, so the
// result is the same for any thread count or executor. The observer sees OnWaveStart (wave 0,
// candidates = the number of configurations), OnBatch after every batch (progress only: no
// particles), OnWaveEnd with Wave(), and is polled by ShouldStop between batches.
EnumerationResult Enumerate(const SmcProblem& problem,
                            const EnumerationOptions& options,
                            SmcObserver* observer = nullptr);

}  // namespace combabc
