#pragma once
// Options for combinatorial ABC-SMC (and ABC rejection, its one-wave special case).
// Every field has a default; IsValid() checks them all before any work and names the field.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"

#include "combabc/proposals/proposal_options.hpp"
#include "combabc/samplers/multi_fidelity.hpp"
#include "combabc/schedules/tempering_schedule.hpp"
#include "combabc/schedules/threshold_schedule.hpp"

namespace combabc {

// Which estimate of the ABC posterior a wave reports and the next wave's proposal uses.
enum class Estimator {
  kPaper,       // accepted particles unweighted, as in the paper (Eq. 2 fractions)
  kImportance,  // each accepted particle weighted by p(theta)/q(theta), normalised
};
template <>
struct EnumNames<Estimator> {
  static constexpr std::pair<Estimator, const char*> kNames[] = {
      {Estimator::kPaper, "paper"},
      {Estimator::kImportance, "importance"},
  };
};

// How each wave after the first reaches its target (docs/algorithm.md, "Resample-move").
enum class SamplerMethod {
  // Every wave draws fresh candidates from a kernel fitted to the previous wave and keeps those
  // within its thresholds (the paper's section 3).
  kRejection,
  // Resample-move SMC (Del Moral, Doucet & Jasra 2012; Chopin 2002): the previous wave's
  // particles are reweighted to the new target, resampled, and moved by Metropolis-Hastings
  // steps that leave it invariant, so that particles which fit are kept rather than drawn anew.
  kResampleMove,
};
template <>
struct EnumNames<SamplerMethod> {
  static constexpr std::pair<SamplerMethod, const char*> kNames[] = {
      {SamplerMethod::kRejection, "rejection"},
      {SamplerMethod::kResampleMove, "resample_move"},
  };
};

// Whether a resample-move run ends with an independent wave (MoveOptions::final_wave).
enum class FinalWave {
  // When its predicted cost is at most MoveOptions::kFinalWaveShare of the run's simulations.
  kAuto,
  kAlways,
  kNever,
};
template <>
struct EnumNames<FinalWave> {
  static constexpr std::pair<FinalWave, const char*> kNames[] = {
      {FinalWave::kAuto, "auto"},
      {FinalWave::kAlways, "always"},
      {FinalWave::kNever, "never"},
  };
};

// The resample-move waves' options (SamplerMethod::kResampleMove).
struct MoveOptions {
  // Each wave's step toward the schedule's next thresholds or temperatures is shortened, where
  // needed, so that the reweighted particles keep at least this fraction of the previous wave's
  // effective sample size (Del Moral, Doucet & Jasra 2012's alpha).
  double ess_fraction = 0.5;
  // Metropolis-Hastings rounds (every particle one proposal each) continue until a particle has
  // moved at least once with probability 1 - stay_probability at the measured acceptance rate
  // (Drovandi & Pettitt 2011), within [1, max_rounds].
  double stay_probability = 0.05;
  int max_rounds = 30;
  // The share of proposals drawn from the kernel fitted to the reweighted particles (an
  // independent Metropolis-Hastings proposal, Schaefer & Chopin 2013); the rest are local: one or
  // two bits flipped, chosen by the particles' marginals and correlations, or a random walk on
  // the reals.
  double independent_share = 0.5;
  // Where the reweighted particles keep fewer than this fraction of n_t as their effective sample
  // size (a list schedule's step too large), the wave draws fresh candidates by rejection instead.
  double min_survivor_fraction = 0.02;
  // Once a move wave reaches the target, one more wave at the same thresholds draws fresh
  // candidates by rejection from the ancestor kernel fitted to the moved particles: independent
  // draws given that population, so their Monte-Carlo errors need no clustering by ancestor,
  // which moves never undo (docs/algorithm.md, "The final wave"). kAuto draws it when the last
  // move wave's independent proposals predict that it costs at most kFinalWaveShare of the
  // simulations so far.
  FinalWave final_wave = FinalWave::kAuto;
  static constexpr double kFinalWaveShare = 0.25;

  // Fills `error` (may be null) with the first field that fails.
  bool IsValid(ValidationError* error) const;
  // The same check as a sentence ("MoveOptions::field = value; constraint").
  bool IsValid(std::string* why) const;
};

struct SmcOptions {
  // Maximum number of waves (t = 0..num_waves-1). With list thresholds, each list has exactly
  // this many entries.
  int num_waves = 5;
  // n_t: accepted particles per wave (paper: 500).
  int accepted_per_wave = 500;
  // When not empty: n_t for each wave, num_waves entries (each >= 1), in place of
  // accepted_per_wave (e.g. a large first wave to explore the prior, smaller ones after).
  std::vector<int> accepted_by_wave;
  // One schedule per *threshold* component of the distance, in component order (indicator
  // components need none). Empty = one default quantile schedule for each.
  std::vector<ThresholdSchedule> thresholds;
  TemperingSchedule tempering;
  // The kernels that fit each wave's proposal to the previous wave (Eq. 2 by default).
  ProposalOptions proposal;
  Estimator estimator = Estimator::kImportance;
  // Root of every random stream: candidate i of wave t draws from RandomStream(seed, t, i).
  std::uint64_t seed = 1;
  // Worker threads (0 = all cores). The history does not depend on it.
  int threads = 1;
  // Runs always end by default (docs/algorithm.md, "Stopping"): a budget, an acceptance-rate
  // floor and a failure ceiling. Each check is made candidate by candidate in index order, so
  // where a run stops does not depend on threads or batch sizes.
  // Stop once this many candidates have been simulated in all (0 = no limit).
  std::int64_t max_simulations = 10'000'000;
  // Give up on a wave whose acceptance rate (accepted / candidates so far) is below this once it
  // has simulated acceptance_floor_after candidates (0 = never).
  double min_acceptance_rate = 1e-4;
  // Candidates a wave simulates before the floor applies: about 10 / min_acceptance_rate, so that
  // a wave at the floor has about 10 acceptances to be judged on, not a handful of candidates.
  std::int64_t acceptance_floor_after = 100'000;
  // Stop when more than this fraction of the run's simulations failed (SimulationFailed, NaN
  // output), judged once the run has simulated failure_fraction_after candidates (1 = never).
  double max_failure_fraction = 0.1;
  std::int64_t failure_fraction_after = 100;
  // Stop at the first batch boundary after this many seconds (0 = no limit).
  double max_wall_time_s = 0.0;
  // Candidates simulated between two checkpoints (observer OnBatch calls). 0 = automatic,
  // sized from the expected acceptance rate. Does not change the history.
  int batch_size = 0;
  // Keep each accepted particle's simulated output in the history.
  bool keep_outputs = true;
  // Rejection waves (the paper's) or resample-move waves after wave 0.
  SamplerMethod method = SamplerMethod::kRejection;
  MoveOptions moves;
  // The continuation probabilities of a run with a low-fidelity simulator
  // (SmcProblem::low_fidelity), their tuning, floor and cost ratio; unused without one.
  MultiFidelityOptions multi_fidelity;

  // On failure `error` names the field (owner "SmcOptions"), with the member path below it:
  // "accepted_by_wave[2]", "thresholds[1].values", "proposal.logistic.clip".
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "SmcOptions::field = value; constraint".
  bool IsValid(std::string* why) const;
  // n_t of wave t: accepted_by_wave[t] when given, else accepted_per_wave.
  int AcceptedIn(int wave) const {
    return accepted_by_wave.empty() ? accepted_per_wave
                                    : accepted_by_wave.at(static_cast<std::size_t>(wave));
  }
};

}  // namespace combabc
