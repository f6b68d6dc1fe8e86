// Combinatorial ABC-SMC, Shamas et al. 2024 section 3. See docs/algorithm.md for the derivations.
#include "combabc/samplers/combinatorial_smc.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/proposals/proposal_options.hpp"
#include "combabc/samplers/mode_loss.hpp"
#include "combabc/samplers/multi_fidelity.hpp"
#include "proposals/log_sum_exp.hpp"
#include "samplers/candidate_batch.hpp"
#include "samplers/continuation_tuning.hpp"
#include "samplers/move_step.hpp"

namespace combabc {
namespace {

// A wave's effective number of accepted candidates, (sum m)^2 / sum m^2 over its particles'
// multipliers m (docs/algorithm.md, "Multi-fidelity sampling"): a wave ends when it reaches
// accepted_per_wave. In a single-fidelity run every m is 1 and it is exactly the particle count
// (k^2 / k in floating point), so the rule is "n accepted"; the signed and 1/eta multipliers of a
// multi-fidelity run count for less, so that its wave ends at the Monte-Carlo accuracy of n
// expensive acceptances (Prescott & Baker also end a generation on an ESS).
class EffectiveCount {
 public:
  void Add(double m) {
    sum_ += m;
    sum_sq_ += m * m;
  }
  // A sum <= 0 (more false-positive weight than agreement so far) is not there yet.
  bool Reached(int n) const { return sum_ > 0.0 && sum_ * sum_ >= n * sum_sq_; }
  double value() const { return sum_ > 0.0 ? sum_ * sum_ / sum_sq_ : 0.0; }

 private:
  double sum_ = 0.0;
  double sum_sq_ = 0.0;
};

using Clock = std::chrono::steady_clock;

// A quantile temperature schedule falls at least by this factor per wave (docs/algorithm.md).
constexpr double kMaxTemperatureRatio = 0.5;
// Bounds on one worker's share of an automatic batch, in seconds of simulation (BatchSize).
constexpr double kMinBatchSeconds = 0.05;
constexpr double kMaxBatchSeconds = 5.0;
// Acceptances after which a wave's batches are sized from its own acceptance rate.
constexpr std::size_t kOwnRateAfter = 10;
// The confirmed candidates of one class (cheap model accepted / rejected) a wave needs before the
// tuning may lower that class's continuation probability (ChooseNextContinuation).
constexpr std::int64_t kMinConfirmations = 20;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

std::string Describe(int wave, const SimulationFailure& failure) {
  return "wave " + std::to_string(wave + 1) + ", candidate " + std::to_string(failure.index) +
         ": " + failure.reason;
}

using Stop = std::optional<std::pair<Termination, std::string>>;

// The failure ceiling, then the acceptance floor, over the run's state: `total` simulations with
// `failures` failed in all, wave `wave` having accepted `accepted` of its `candidates`. One rule
// for the engine (candidate by candidate) and for ImmediateStop (before a resume).
Stop FailureOrFloorStop(const SmcOptions& options,
                        std::int64_t total,
                        std::int64_t failures,
                        const std::string& last_failure,
                        int wave,
                        std::int64_t candidates,
                        std::int64_t accepted) {
  if (options.max_failure_fraction < 1.0 && total >= options.failure_fraction_after &&
      static_cast<double>(failures) > options.max_failure_fraction * static_cast<double>(total)) {
    char fraction[64];
    std::snprintf(fraction,
                  sizeof fraction,
                  " (%.1f %% > %.4g %%)",
                  100.0 * static_cast<double>(failures) / static_cast<double>(total),
                  100.0 * options.max_failure_fraction);
    return Stop({Termination::kTooManyFailures,
                 std::to_string(failures) + " of " + std::to_string(total) + " simulations failed" +
                     fraction + "; last failure: " + last_failure});
  }
  if (options.min_acceptance_rate > 0 && candidates >= options.acceptance_floor_after &&
      static_cast<double>(accepted) <
          options.min_acceptance_rate * static_cast<double>(candidates)) {
    char rate[96];
    std::snprintf(rate,
                  sizeof rate,
                  " candidates (rate %.3g), below min_acceptance_rate = %.3g",
                  static_cast<double>(accepted) / static_cast<double>(candidates),
                  options.min_acceptance_rate);
    return Stop({Termination::kAcceptanceRateTooLow,
                 "wave " + std::to_string(wave + 1) + " accepted " + std::to_string(accepted) +
                     " of " + std::to_string(candidates) + rate});
  }
  return std::nullopt;
}

std::string BudgetMessage(const SmcOptions& options, int wave) {
  return "simulation budget of " + std::to_string(options.max_simulations) + " reached in wave " +
         std::to_string(wave + 1);
}

class SmcRun {
 public:
  SmcRun(const SmcProblem& problem, const SmcOptions& options, SmcObserver* observer)
      : space_(*problem.space),
        simulator_(*problem.simulator),
        low_fidelity_(problem.low_fidelity),
        start_population_(problem.start),
        distance_(*problem.distance),
        options_(options),
        observer_(observer),
        components_(distance_.components()) {
    if (problem.kernel) {
      kernel_ = problem.kernel;
    } else {
      owned_kernel_ = MakeJointKernel(options_.proposal, space_);
      kernel_ = owned_kernel_.get();
    }
    if (problem.executor) {
      executor_ = problem.executor;
    } else {
      owned_executor_ = std::make_unique<ThreadPoolExecutor>(options_.threads);
      executor_ = owned_executor_.get();
    }
    if (space_.num_reals() > 0 && options_.estimator == Estimator::kPaper) {
      // Unweighted fractions are the paper's estimator for Eq. 2; a continuous kernel perturbs
      // particles, and only importance weights correct for that.
      throw Error(ErrorKind::kConfig,
                  "the paper estimator is unweighted; continuous parameters need importance "
                  "weights (estimator = importance)",
                  "",
                  0,
                  "SmcOptions::estimator");
    }
    if (options_.method == SamplerMethod::kResampleMove) {
      // Moves keep the previous wave's particles as draws from its target: they need the
      // importance weights that make them so, and one simulator whose acceptance is the target.
      if (options_.estimator == Estimator::kPaper) {
        throw Error(ErrorKind::kConfig,
                    "resample-move waves need importance weights (estimator = importance); the "
                    "paper estimator's equal weights are not draws from the wave's target",
                    "",
                    0,
                    "SmcOptions::method");
      }
      if (low_fidelity_) {
        throw Error(ErrorKind::kConfig,
                    "resample-move waves do not apply to a multi-fidelity run (its weights are "
                    "signed and its acceptance is two simulators')",
                    "",
                    0,
                    "SmcOptions::method");
      }
    }
    for (std::size_t k = 0; k < components_.size(); ++k) {
      if (components_[k].kind != ComponentKind::kIndicator) threshold_components_.push_back(k);
      if (components_[k].kind == ComponentKind::kNegLogLikelihood) stochastic_ = true;
    }
    schedules_ = options_.thresholds;
    if (schedules_.empty()) {
      schedules_.resize(threshold_components_.size());
      // A temperature ends at 1, where the acceptance is the likelihood itself.
      for (std::size_t s = 0; s < schedules_.size(); ++s) {
        if (IsLikelihood(s)) schedules_[s].target = 1.0;
      }
    }
    if (schedules_.size() != threshold_components_.size()) {
      throw Error(ErrorKind::kConfig,
                  "has " + std::to_string(schedules_.size()) + " schedules; the distance has " +
                      std::to_string(threshold_components_.size()) +
                      " threshold and likelihood components",
                  "",
                  0,
                  "SmcOptions::thresholds");
    }
    for (std::size_t s = 0; s < schedules_.size(); ++s) {
      if (!IsLikelihood(s)) continue;
      const auto& schedule = schedules_[s];
      const bool below_one = schedule.kind == ThresholdKind::kList
                                 ? std::any_of(schedule.values.begin(),
                                               schedule.values.end(),
                                               [](double v) { return !(v >= 1.0); })
                                 : !(schedule.target >= 1.0);
      if (below_one) {
        throw Error(ErrorKind::kConfig,
                    "component \"" + components_[threshold_components_[s]].name +
                        "\" is a likelihood: its schedule holds temperatures, which must be >= 1 "
                        "(T = 1 is the posterior under the error model)",
                    "",
                    0,
                    "SmcOptions::thresholds[" + std::to_string(s) + "]");
      }
    }
    if (simulator_.output_size() < 0) {
      throw Error(ErrorKind::kConfig, "simulator output_size() is negative");
    }
    if (low_fidelity_ && low_fidelity_->output_size() != simulator_.output_size()) {
      throw Error(ErrorKind::kConfig,
                  "has " + std::to_string(low_fidelity_->output_size()) +
                      " outputs; the simulator has " + std::to_string(simulator_.output_size()) +
                      " (the one distance measures both)",
                  "",
                  0,
                  "SmcProblem::low_fidelity");
    }
  }

  RunHistory Run(const ResumePoint* resume) {
    start_ = Clock::now();
    RunHistory history;
    int first_wave = 0;
    if (resume) {
      history.waves = resume->completed;
      // Not stored: derived from the ancestors, as the move waves' errors and Eves need.
      AssignEveIndices(history.waves);
      for (const auto& w : history.waves) {
        total_ += w.candidates;
        discarded_ += w.discarded;
        failures_ += static_cast<std::int64_t>(w.failures.size());
        if (!w.failures.empty()) last_failure_ = Describe(w.wave, w.failures.back());
        if (!w.complete) throw Error(ErrorKind::kData, "resume point holds an incomplete wave");
      }
      first_wave = static_cast<int>(history.waves.size());
      // The next wave sizes its first batch from this rate, as the uninterrupted run did.
      if (!history.waves.empty()) last_rate_ = history.waves.back().acceptance_rate;
      if (!history.waves.empty() && Done(history.waves.back())) {
        return Finish(std::move(history), Termination::kTargetReached, "target threshold reached");
      }
    }
    if (start_population_ && first_wave == 0) {
      // Wave 0 is the finished run's posterior, re-simulated; cut short, it is done again.
      WaveRecord wave = StartFromPopulation();
      const bool complete = wave.complete;
      history.waves.push_back(std::move(wave));
      if (!complete) {
        return Finish(std::move(history), start_stop_->first, start_stop_->second);
      }
      first_wave = 1;
    }
    for (int t = first_wave; t < options_.num_waves; ++t) {
      const WaveRecord* previous = t > 0 ? &history.waves.back() : nullptr;
      if (std::optional<WaveRecord> moving = StartMoveWave(t, previous, history.waves)) {
        // A move wave is not checkpointed within: a resumed run does it again from its start
        // (the same rounds, from the same streams), whatever a partial record of it holds.
        const auto stop = MoveWave(*moving, *previous);
        history.waves.push_back(std::move(*moving));
        if (stop) return Finish(std::move(history), stop->first, stop->second);
        if (Done(history.waves.back())) {
          return Finish(
              std::move(history), Termination::kTargetReached, "target threshold reached");
        }
        continue;
      }
      WaveRecord wave = StartWave(t, previous, history.waves);
      std::int64_t next_index = 0;
      if (resume && resume->has_partial && resume->partial_wave == t) {
        // Its continuation probabilities and costs so far: the wave goes on with the
        // probabilities it started with.
        if (low_fidelity_ && resume->partial_fidelity) {
          wave.multi_fidelity = resume->partial_fidelity;
        }
        wave.particles = resume->partial_accepted;
        next_index = resume->partial_next_index;
        // Killed after the wave's last batch but before it ended: its overshoot still counts.
        wave.discarded = resume->partial_discarded;
        discarded_ += wave.discarded;
        wave.failures = resume->partial_failures;
        total_ += next_index;
        failures_ += static_cast<std::int64_t>(wave.failures.size());
        if (!wave.failures.empty()) last_failure_ = Describe(t, wave.failures.back());
      }
      const auto stop = RunWave(wave, next_index, history.waves);
      history.waves.push_back(std::move(wave));
      if (stop) return Finish(std::move(history), stop->first, stop->second);
      if (AllFinal(history.waves.back())) {
        return Finish(std::move(history), Termination::kTargetReached, "target threshold reached");
      }
    }
    return Finish(std::move(history),
                  Termination::kMaxWaves,
                  "all " + std::to_string(options_.num_waves) + " waves done above the target");
  }

 private:
  // Whether the run ends after `wave`: it is at the target, and no final independent wave
  // (MoveOptions::final_wave) is still to come after it.
  bool Done(const WaveRecord& wave) const { return AllFinal(wave) && !RefreshAfter(wave); }

  // Whether the final independent wave follows `wave`: a move wave at the target, with a wave
  // left, and (FinalWave::kAuto) affordable. Its acceptance rate is predicted by that of the move
  // wave's independent proposals, which come from kernels fitted to the same particles: on the
  // sensor-design example 79 % predicted 36 %, on the chain toy 0.5 % predicted 0.6 %. Decided
  // from the stored history alone, so that a resumed run decides alike.
  bool RefreshAfter(const WaveRecord& wave) const {
    const FinalWave mode = options_.moves.final_wave;
    if (options_.method != SamplerMethod::kResampleMove || mode == FinalWave::kNever ||
        !wave.moves || !AllFinal(wave) || wave.wave + 1 >= options_.num_waves) {
      return false;
    }
    if (mode == FinalWave::kAlways) return true;
    const WaveMoves& m = *wave.moves;
    if (m.independent_accepted <= 0) return false;
    const double rate =
        static_cast<double>(m.independent_accepted) / static_cast<double>(m.independent_proposed);
    const double cost = static_cast<double>(options_.AcceptedIn(wave.wave + 1)) / rate;
    return cost <= MoveOptions::kFinalWaveShare * static_cast<double>(total_);
  }

  bool AllFinal(const WaveRecord& wave) const {
    for (std::size_t s = 0; s < schedules_.size(); ++s) {
      if (!schedules_[s].IsFinal(wave.wave, wave.thresholds[s])) return false;
    }
    return true;
  }

  bool IsLikelihood(std::size_t s) const {
    return components_[threshold_components_[s]].kind == ComponentKind::kNegLogLikelihood;
  }

  // Wave t's thresholds, and into `offsets` its m_k per schedule slot, from the waves before it:
  // `previous` (wave t - 1, null for wave 0) and the `earlier` ones. The one rule for starting a
  // wave and for tuning the previous wave's continuation probabilities for it.
  std::vector<double> Thresholds(int t,
                                 const WaveRecord* previous,
                                 std::span<const WaveRecord> earlier,
                                 std::vector<double>& offsets) const {
    std::vector<double> thresholds;
    std::vector<double> column;
    std::vector<double> weights;  // a multi-fidelity wave's, for its confirmed distances
    std::vector<double> importance;
    offsets.assign(schedules_.size(), 0.0);
    for (std::size_t s = 0; s < schedules_.size(); ++s) {
      const std::size_t k = threshold_components_[s];
      if (IsLikelihood(s)) {
        // m_k: the best likelihood found so far stands in for the unknown max over theta
        // (pyABC's pdf_norm_max_found), so that acceptance at T = 1 is not astronomically rare.
        double best = std::numeric_limits<double>::infinity();
        auto scan = [&](const WaveRecord& w) {
          for (const auto& p : w.particles) best = std::min(best, p.distance[k]);
        };
        for (const auto& w : earlier) scan(w);
        if (previous) scan(*previous);
        if (std::isfinite(best)) offsets[s] = best;
      }
      column.clear();
      weights.clear();
      importance.clear();
      if (previous) {
        // A multi-fidelity wave: the expensive distances of its confirmed particles with a
        // positive multiplier (the thresholds are the expensive model's; a cheap model far from
        // it would otherwise set one the expensive model never meets), or, with none confirmed,
        // every particle with a positive multiplier (docs/algorithm.md, "Multi-fidelity
        // sampling"); a single-fidelity wave: all of them.
        const bool confirmed = std::any_of(previous->particles.begin(),
                                           previous->particles.end(),
                                           [](const Particle& p) { return p.confirmed; });
        // The confirmed ones count 1 / their continuation probability: they stand for the
        // particles of their kind that were not confirmed (a quantile over them alone would
        // lean to the false negatives, confirmed far more often when eta_1 is small).
        for (const auto& p : previous->particles) {
          if (p.multiplier > 0.0 && (p.confirmed || !confirmed)) {
            column.push_back(p.distance[k] - offsets[s]);
            importance.push_back(p.weight);
            if (confirmed) weights.push_back(InverseContinuation(p, *previous));
          }
        }
      }
      PreviousWave last{.distances = column, .counts = weights, .importance = importance};
      if (previous) last.acceptance_rate = previous->acceptance_rate;
      double eps = schedules_[s].ThresholdFor(t, last);
      if (IsLikelihood(s) && schedules_[s].kind != ThresholdKind::kList && previous) {
        // Near the posterior the quantile of d - m can exceed T (many configurations within a
        // few T): force a geometric decrease so the schedule cannot stall above 1.
        eps = std::max(schedules_[s].target,
                       std::min(eps, kMaxTemperatureRatio * previous->thresholds[s]));
      }
      thresholds.push_back(eps);
    }
    return thresholds;
  }

  WaveRecord StartWave(int t, const WaveRecord* previous, const std::vector<WaveRecord>& done) {
    WaveRecord wave;
    wave.wave = t;
    // `previous` is done's last wave.
    const std::span<const WaveRecord> earlier(done.data(), previous ? done.size() - 1 : 0);
    wave.thresholds = Thresholds(t, previous, earlier, offsets_);
    if (low_fidelity_) {
      // Wave 0 continues with the options' probabilities, every later wave with those its
      // previous wave chose for it (stored with it, so that a resumed run needs no recomputing).
      WaveFidelity fidelity;
      fidelity.continue_if_accepted = options_.multi_fidelity.continue_if_accepted;
      fidelity.continue_if_rejected = options_.multi_fidelity.continue_if_rejected;
      if (previous && previous->multi_fidelity) {
        fidelity.continue_if_accepted = previous->multi_fidelity->next_continue_if_accepted;
        fidelity.continue_if_rejected = previous->multi_fidelity->next_continue_if_rejected;
      }
      wave.multi_fidelity = fidelity;
    }
    wave.phi = options_.tempering.Phi(t, options_.num_waves);
    if (!previous || previous->particles.empty()) {
      // Wave 0 proposes from the prior.
      proposal_ = kernel_->Prior(space_);
      from_prior_ = true;
    } else {
      // Eq. 2 generalised: the kernel fits the previous wave's weighted particles; the bits are
      // tempered toward the prior (Eq. 3). The final independent wave redraws the moved
      // particles with the ancestor kernel, a mixture around each of them, whose weights
      // p A / q stay the most even: on the sensor-design example (4 experiments) its ESS was 475
      // of 500 where the fitted product kernel's was 363 and the logistic one's 336.
      const Population population = MakePopulation(*previous, wave.thresholds);
      const JointKernel& kernel = RefreshAfter(*previous) ? AncestorKernel() : *kernel_;
      proposal_ = kernel.Fit(population, space_, Tempering{wave.phi, options_.tempering.form});
      from_prior_ = false;
      if (population.num_free_bits > 0) {
        wave.pattern_classes = FindPatternClasses(
            population,
            [&](std::span<const std::uint8_t> bits, std::span<const double> reals) {
              return proposal_->LogDensity(bits, reals) - space_.LogPriorBits(bits) -
                     space_.LogPriorReals(reals);
            },
            [&](std::span<const std::uint8_t> bits) {
              return proposal_->LogBitsDensity(bits) - space_.LogPriorBits(bits);
            },
            options_.AcceptedIn(wave.wave),
            PaperReweight(*previous));
        for (PatternClass& c : wave.pattern_classes) {
          std::vector<std::uint8_t> full(static_cast<std::size_t>(space_.binary().dimension()));
          space_.binary().Expand(c.bits, full);
          c.bits = std::move(full);
        }
      }
    }
    wave.proposal = proposal_->Marginals();
    if (observer_) observer_->OnWaveStart(wave);
    return wave;
  }

  // The paper estimator's equal weights stand for the previous wave's proposal times its
  // acceptance, not for the posterior: the mode-loss shares then take each particle's log p/q
  // (FindPatternClasses). Empty for the importance estimator.
  std::vector<double> PaperReweight(const WaveRecord& previous) const {
    std::vector<double> log_weight;
    if (options_.estimator != Estimator::kPaper) return log_weight;
    for (const auto& p : previous.particles) log_weight.push_back(p.log_weight);
    return log_weight;
  }

  // The previous wave's particles as the kernels see them: free bits, reals, the estimator's
  // normalised weights, and which particles the new thresholds would still accept.
  Population MakePopulation(const WaveRecord& previous,
                            const std::vector<double>& thresholds) const {
    Population pop;
    pop.size = previous.particles.size();
    pop.num_free_bits = static_cast<std::size_t>(space_.num_free_bits());
    pop.num_reals = static_cast<std::size_t>(space_.num_reals());
    pop.free_bits.resize(pop.size * pop.num_free_bits);
    pop.reals.reserve(pop.size * pop.num_reals);
    for (std::size_t i = 0; i < pop.size; ++i) {
      const auto& p = previous.particles[i];
      const bool tied = space_.binary().Reduce(
          p.theta.bits, std::span(pop.free_bits.data() + i * pop.num_free_bits, pop.num_free_bits));
      COMBABC_CHECK(tied);
      pop.reals.insert(pop.reals.end(), p.theta.reals.begin(), p.theta.reals.end());
      pop.weights.push_back(p.weight);
      pop.within_next.push_back(Within(p.distance, thresholds) ? 1 : 0);
    }
    // A multi-fidelity wave may hold negative weights, which no proposal can take as
    // probabilities: the kernels fit the positive part, renormalised, as Prescott & Baker (2021,
    // arXiv:2001.06256) build the next importance distribution. The proposal only has to cover
    // the posterior; the importance weights p/q of the next wave correct for whichever it is.
    if (std::any_of(pop.weights.begin(), pop.weights.end(), [](double w) { return w < 0; })) {
      double sum = 0.0;
      for (auto& w : pop.weights) {
        w = std::max(w, 0.0);
        sum += w;
      }
      for (auto& w : pop.weights) w /= sum;
    }
    return pop;
  }

  // Whether candidate distances d pass the thresholds eps; likelihood components pass with
  // probability exp(-sum_k (d_k - m_k) / T_k), decided by the candidate's uniform u.
  bool Accept(std::span<const double> d, const std::vector<double>& eps, double u) const {
    const double log_accept = LogAcceptance(d, eps, offsets_);
    if (log_accept == -std::numeric_limits<double>::infinity()) return false;
    return !stochastic_ || u < std::exp(log_accept);
  }

  // The probability that Accept(d, eps, u) holds for u uniform, with `offsets` the m_k.
  double AcceptanceProbability(std::span<const double> d,
                               const std::vector<double>& eps,
                               const std::vector<double>& offsets) const {
    const double log_accept = LogAcceptance(d, eps, offsets);
    if (log_accept == -std::numeric_limits<double>::infinity()) return 0.0;
    return stochastic_ ? std::exp(log_accept) : 1.0;
  }

  // The log of a resample-move wave's target, up to a constant: LogWeight without offsets. A
  // Metropolis-Hastings ratio is not a probability and may exceed 1, so it needs no offset m_k: a
  // clamped exp(-max(d - m, 0) / T) would make every configuration better than the best seen so
  // far equally likely.
  double LogTarget(std::span<const double> d, const std::vector<double>& eps) const {
    return LogWeight(d, eps, nullptr);
  }

  // The log of the likelihood components' acceptance probability (0 without any): LogWeight with
  // the offsets m_k, the excess d - m clamped at 0.
  double LogAcceptance(std::span<const double> d,
                       const std::vector<double>& eps,
                       const std::vector<double>& offsets) const {
    return LogWeight(d, eps, &offsets);
  }

  // -inf when a threshold or indicator component rejects d; else -sum_k e_k / T_k over the
  // likelihood components, e_k = max(d_k - m_k, 0) with `offsets` (m_k), d_k without.
  double LogWeight(std::span<const double> d,
                   const std::vector<double>& eps,
                   const std::vector<double>* offsets) const {
    constexpr double kReject = -std::numeric_limits<double>::infinity();
    double log_weight = 0.0;
    std::size_t s = 0;
    for (std::size_t k = 0; k < components_.size(); ++k) {
      switch (components_[k].kind) {
        case ComponentKind::kThreshold:
          if (!(d[k] <= eps[s++])) return kReject;
          break;
        case ComponentKind::kIndicator:
          if (d[k] != components_[k].required) return kReject;
          break;
        case ComponentKind::kNegLogLikelihood: {
          const double temperature = eps[s];
          const double excess = offsets ? d[k] - (*offsets)[s] : d[k];
          ++s;
          if (std::isinf(temperature)) break;  // T = inf: the prior's wave accepts all
          if (!(excess < std::numeric_limits<double>::infinity())) return kReject;
          log_weight -= (offsets ? std::max(excess, 0.0) : excess) / temperature;
          break;
        }
      }
    }
    return log_weight;
  }

  // Candidate i's weight multiplier: without a low-fidelity simulator 1 if accepted, 0 if not;
  // with one, MultiFidelityMultiplier of its cheap and (if continued) expensive acceptance. A
  // wave keeps every candidate whose multiplier is not 0 as a particle: the first n of them in
  // index order are n independent draws given a non-zero multiplier, over which the weighted
  // estimates are the same ratios as over all candidates.
  double Multiplier(const CandidateBatch& batch, std::int64_t i, const WaveRecord& wave) const {
    const auto& eps = wave.thresholds;
    if (!low_fidelity_) return Accept(batch.distance(i), eps, batch.uniform(i)) ? 1.0 : 0.0;
    const bool continued = batch.continued(i);
    const bool expensive_accepted = continued && Accept(batch.distance(i), eps, batch.uniform(i));
    return MultiFidelityMultiplier(
        Continuation(wave), batch.cheap_accepted(i), continued, expensive_accepted);
  }

  // The multi-fidelity options with the continuation probabilities of `wave`.
  MultiFidelityOptions Continuation(const WaveRecord& wave) const {
    MultiFidelityOptions o = options_.multi_fidelity;
    o.continue_if_accepted = wave.multi_fidelity->continue_if_accepted;
    o.continue_if_rejected = wave.multi_fidelity->continue_if_rejected;
    return o;
  }

  // The deterministic version for the kernels (OLCM's "still within the next thresholds"): a
  // likelihood component counts as within when d_k - m_k <= T_k.
  bool Within(std::span<const double> d, const std::vector<double>& eps) const {
    std::size_t s = 0;
    for (std::size_t k = 0; k < components_.size(); ++k) {
      if (components_[k].kind == ComponentKind::kIndicator) {
        if (d[k] != components_[k].required) return false;
        continue;
      }
      const double offset = components_[k].kind == ComponentKind::kThreshold ? 0.0 : offsets_[s];
      if (!(d[k] - offset <= eps[s++])) return false;
    }
    return true;
  }

  // The automatic batch size (docs/algorithm.md, "Batch size"): the candidates the wave is
  // expected to still need, within bounds set by the measured cost of a simulation. Only how many
  // candidates past the wave's last acceptance get simulated (and discarded) depends on it, never
  // the history: candidates are accepted in index order.
  // `effective`: the wave's EffectiveCount so far (its particle count in a single-fidelity run).
  std::int64_t BatchSize(const WaveRecord& wave,
                         std::int64_t next_index,
                         double prior_rate,
                         double effective) const {
    if (options_.batch_size > 0) return options_.batch_size;
    const std::int64_t workers = executor_->concurrency();
    // Cost unknown (the run's first batch, or a resume's): one candidate per worker measures it.
    if (!(cost_s_ > 0.0)) return workers;
    const double needed =
        std::max(static_cast<double>(options_.AcceptedIn(wave.wave)) - effective, 1.0);
    // The wave's own rate once it has a few acceptances; before, the previous wave's, which may
    // be far off (thresholds and proposal changed): then only half the candidates it predicts,
    // and the wave's own rate sizes the rest.
    const bool own_rate = wave.particles.size() >= kOwnRateAfter;
    const double rate = std::max(
        own_rate ? std::max(effective, 1.0) / static_cast<double>(next_index) : prior_rate, 1e-4);
    const auto expected = static_cast<std::int64_t>(std::ceil(needed / rate));
    const std::int64_t wanted = own_rate ? expected + expected / 16 : (expected + 1) / 2;
    // At least kMinBatchSeconds of work per worker, so that the fixed cost of a batch (the
    // checkpoint, about 2 ms, and the executor's synchronisation) stays small: 32 candidates per
    // worker for simulations under 1.6 ms, one for those over 50 ms. At most kMaxBatchSeconds, so
    // that a slow simulator's run is checkpointed, shows progress and stops on Ctrl-C often.
    const auto per_worker = [&](double seconds) {
      return static_cast<std::int64_t>(std::clamp(std::ceil(seconds / cost_s_), 1.0, 4096.0));
    };
    const std::int64_t lo = workers * std::min<std::int64_t>(32, per_worker(kMinBatchSeconds));
    const std::int64_t hi =
        std::max(lo, std::min<std::int64_t>(4096, workers * per_worker(kMaxBatchSeconds)));
    return std::clamp<std::int64_t>(wanted, lo, hi);
  }

  // Records the batch just evaluated: `size` candidates in `seconds`. The primary's measure is
  // every worker's, so that all size the next batch alike.
  void MeasureCost(std::int64_t size, double seconds) {
    if (options_.batch_size > 0) return;
    const std::int64_t workers = executor_->concurrency();
    const double rounds = std::ceil(static_cast<double>(size) / static_cast<double>(workers));
    // Never 0, which would mean "unknown" (a batch faster than the clock's resolution).
    cost_s_ = executor_->FromPrimary(std::max(seconds / rounds, 1e-9));
  }

  // The stop, if any, that candidate `index` of `wave` triggers once it is counted (run-wide:
  // total_ candidates and failures_ failures so far, this one included). Checked candidate by
  // candidate in index order, so that where a run stops does not depend on the batch sizes.
  Stop CheckCandidate(const WaveRecord& wave, std::int64_t index) const {
    return FailureOrFloorStop(options_,
                              total_,
                              failures_,
                              last_failure_,
                              wave.wave,
                              index + 1,
                              static_cast<std::int64_t>(wave.particles.size()));
  }

  // The stop of a multi-fidelity wave that holds kMultiFidelityParticlesPerAccepted x n particles
  // and still counts fewer than n effective ones (multi_fidelity.hpp): without it the wave grows
  // without bound, and so do the memory and the history.
  Stop ParticleCapStop(const WaveRecord& wave, int n, const EffectiveCount& effective) const {
    const auto cap =
        static_cast<std::size_t>(kMultiFidelityParticlesPerAccepted) * static_cast<std::size_t>(n);
    if (!low_fidelity_ || wave.particles.size() < cap) return std::nullopt;
    char count[32];
    std::snprintf(count, sizeof count, "%.1f", effective.value());
    return Stop({Termination::kTooManyParticles,
                 "wave " + std::to_string(wave.wave + 1) + " kept " +
                     std::to_string(wave.particles.size()) + " particles (" +
                     std::to_string(kMultiFidelityParticlesPerAccepted) + " x the " +
                     std::to_string(n) + " it needs), whose multi-fidelity weights count only " +
                     count +
                     " effective particles: the expensive model rejects too many of the cheap "
                     "model's acceptances; improve the cheap model or raise "
                     "[sampler.multi_fidelity] floor (docs/algorithm.md, \"Multi-fidelity "
                     "sampling\")"});
  }

  // Simulates wave candidates until n_t (AcceptedIn) are accepted or a stopping rule fires;
  // `done` are the waves before it.
  Stop RunWave(WaveRecord& wave, std::int64_t next_index, std::span<const WaveRecord> done) {
    const auto wave_start = Clock::now();
    const WaveProposal proposal{proposal_.get(), from_prior_};
    const int n = options_.AcceptedIn(wave.wave);
    const double prior_rate = last_rate_;
    Stop stop;
    // With a low-fidelity simulator, the batch decides which candidates continue to the
    // expensive one by this wave's acceptance of their cheap distances.
    LowFidelityStage stage;
    if (low_fidelity_) {
      stage.simulator = low_fidelity_;
      stage.options = Continuation(wave);
      stage.accept = [this, &wave](std::span<const double> d, double u) {
        return Accept(d, wave.thresholds, u);
      };
      stage.infinite_thresholds = InfiniteThresholds(wave);
    }
    CandidateBatch batch(space_,
                         simulator_,
                         distance_,
                         components_.size(),
                         stochastic_,
                         low_fidelity_ ? &stage : nullptr);
    EffectiveCount effective;
    for (const auto& p : wave.particles) effective.Add(p.multiplier);  // a resumed wave's
    while (!effective.Reached(n)) {
      std::int64_t size = BatchSize(wave, next_index, prior_rate, effective.value());
      if (options_.max_simulations > 0) size = std::min(size, options_.max_simulations - total_);
      if (size <= 0) {
        stop = Stop({Termination::kBudgetExhausted, BudgetMessage(options_, wave.wave)});
        break;
      }
      const auto batch_start = Clock::now();
      batch.Evaluate(*executor_, options_.seed, wave.wave, next_index, size, proposal);
      MeasureCost(size, Seconds(batch_start));
      // Accept in index order, never completion order: the first n accepted candidates win.
      const std::size_t before = wave.particles.size();
      const std::size_t failures_before = wave.failures.size();
      std::int64_t consumed = size;
      for (std::int64_t i = 0; i < size; ++i) {
        ++total_;
        if (low_fidelity_) {
          // Every candidate ran the cheap simulator (its call time counts, failed or not).
          auto& fidelity = *wave.multi_fidelity;
          fidelity.expensive_simulations += batch.continued(i) ? 1 : 0;
          fidelity.cheap_seconds += batch.cheap_seconds(i);
          fidelity.expensive_seconds += batch.expensive_seconds(i);
        }
        if (batch.failed(i)) {
          wave.failures.push_back({next_index + i, std::string(batch.reason(i))});
          ++failures_;
          last_failure_ = Describe(wave.wave, wave.failures.back());
        } else if (const double multiplier = Multiplier(batch, i, wave); multiplier != 0.0) {
          wave.particles.push_back(batch.MakeParticle(i, next_index + i, options_.keep_outputs));
          wave.particles.back().multiplier = multiplier;
          effective.Add(multiplier);
          if (effective.Reached(n)) {
            consumed = i + 1;
            break;
          }
        } else if (low_fidelity_ && batch.continued(i) && batch.cheap_accepted(i)) {
          // A false positive weighing 0 (eta_1 = 1): no particle, but the tuning needs it.
          auto& fidelity = *wave.multi_fidelity;
          ++fidelity.unkept_false_positives;
          fidelity.unkept_false_positive_log_w2 =
              LogSumExp(fidelity.unkept_false_positive_log_w2, 2.0 * batch.log_weight(i));
        }
        stop = CheckCandidate(wave, next_index + i);
        if (!stop) stop = ParticleCapStop(wave, n, effective);
        if (stop) {
          consumed = i + 1;
          break;
        }
      }
      wave.discarded += size - consumed;
      discarded_ += size - consumed;
      next_index += consumed;
      wave.candidates = next_index;
      if (observer_) {
        BatchProgress progress{
            wave.wave,
            next_index,
            static_cast<std::int64_t>(wave.particles.size()),
            wave.discarded,
            n,
            total_,
            Seconds(start_),
            static_cast<std::int64_t>(wave.failures.size()),
            std::span<const SimulationFailure>(wave.failures).subspan(failures_before),
            wave.multi_fidelity};
        observer_->OnBatch(progress, std::span<const Particle>(wave.particles).subspan(before));
      }
      // A candidate's stop (budget, floor, failures) is decided from the gathered result rows,
      // which every worker of a distributed executor holds: all stop after the same batch.
      if (stop || effective.Reached(n)) break;
      // The primary's clock and signals decide, so that every worker of a distributed executor
      // stops after the same batch.
      if (executor_->FromPrimary(options_.max_wall_time_s > 0 &&
                                 Seconds(start_) >= options_.max_wall_time_s)) {
        stop = Stop({Termination::kWallTimeExceeded,
                     "wall-time limit reached in wave " + std::to_string(wave.wave + 1)});
        break;
      }
      if (executor_->FromPrimary(observer_ && observer_->ShouldStop())) {
        stop = Stop(
            {Termination::kInterrupted, "interrupted in wave " + std::to_string(wave.wave + 1)});
        break;
      }
    }
    wave.candidates = next_index;
    wave.complete = effective.Reached(n);
    ComputeWaveStatistics(wave, options_.estimator);
    if (low_fidelity_) ChooseNextContinuation(wave, done);
    wave.wall_seconds = Seconds(wave_start);
    last_rate_ = wave.acceptance_rate;
    if (observer_) observer_->OnWaveEnd(wave);
    return stop;
  }

  // Wave 0 from SmcProblem::start: its parameters simulated under this problem (in batches, as a
  // move round's), each kept with its weight (log_weight = log w) unless its simulation failed.
  WaveRecord StartFromPopulation() {
    const auto wave_start = Clock::now();
    const StartPopulation& start = *start_population_;
    if (start.thresholds.size() != schedules_.size() ||
        start.weights.size() != start.thetas.size() || start.thetas.empty()) {
      throw Error(ErrorKind::kConfig,
                  "has " + std::to_string(start.thetas.size()) + " parameters, " +
                      std::to_string(start.weights.size()) + " weights and " +
                      std::to_string(start.thresholds.size()) + " thresholds; the problem has " +
                      std::to_string(schedules_.size()) + " threshold and likelihood components",
                  "",
                  0,
                  "SmcProblem::start");
    }
    const std::size_t n = start.thetas.size();
    const std::size_t f = static_cast<std::size_t>(space_.num_free_bits());
    const std::size_t r = static_cast<std::size_t>(space_.num_reals());
    std::vector<std::uint8_t> free(n * f);
    std::vector<double> reals(n * r);
    for (std::size_t i = 0; i < n; ++i) {
      const ParameterValue& theta = start.thetas[i];
      if (theta.reals.size() != r ||
          !space_.binary().Reduce(theta.bits, std::span(free.data() + i * f, f))) {
        throw Error(ErrorKind::kConfig,
                    "parameter " + std::to_string(i) + " does not fit the problem's space",
                    "",
                    0,
                    "SmcProblem::start");
      }
      std::copy(theta.reals.begin(), theta.reals.end(), reals.begin() + i * r);
    }
    WaveRecord wave;
    wave.wave = 0;
    wave.thresholds = start.thresholds;
    offsets_.assign(schedules_.size(), 0.0);
    proposal_ = kernel_->Prior(space_);
    from_prior_ = true;
    wave.proposal = proposal_->Marginals();
    if (observer_) observer_->OnWaveStart(wave);
    CandidateBatch batch(space_, simulator_, distance_, components_.size());
    const WaveProposal given{.given_free = free,
                             .given_reals = reals,
                             .given = true,
                             .stream = MoveStream(0, kStartRound, true)};
    const auto count = static_cast<std::int64_t>(n);
    std::int64_t next = 0;
    while (next < count && !start_stop_) {
      const std::int64_t size = std::min(count - next, MoveBatchSize());
      const auto batch_start = Clock::now();
      batch.Evaluate(*executor_, options_.seed, 0, next, size, given);
      MeasureCost(size, Seconds(batch_start));
      const std::size_t before = wave.particles.size();
      const std::size_t failures_before = wave.failures.size();
      for (std::int64_t j = 0; j < size; ++j) {
        const auto i = static_cast<std::size_t>(next + j);
        ++total_;
        ++wave.candidates;
        if (batch.failed(j)) {
          wave.failures.push_back({next + j, std::string(batch.reason(j))});
          ++failures_;
          last_failure_ = Describe(0, wave.failures.back());
        } else if (start.weights[i] > 0.0 &&
                   LogAcceptance(batch.distance(j), wave.thresholds, offsets_) >
                       -std::numeric_limits<double>::infinity()) {
          if (!start.expected.empty()) CheckResimulated(start.expected.at(i), batch.distance(j), i);
          Particle p = batch.MakeParticle(j, next + j, options_.keep_outputs);
          p.log_weight = std::log(start.weights[i]);
          wave.particles.push_back(std::move(p));
        }
        start_stop_ = FailureOrFloorStop(
            options_, total_, failures_, last_failure_, 0, wave.candidates, count);
        if (start_stop_) break;
      }
      next += size;
      if (observer_) {
        BatchProgress progress{
            0,
            wave.candidates,
            static_cast<std::int64_t>(wave.particles.size()),
            0,
            static_cast<int>(count),
            total_,
            Seconds(start_),
            static_cast<std::int64_t>(wave.failures.size()),
            std::span<const SimulationFailure>(wave.failures).subspan(failures_before),
            std::nullopt};
        observer_->OnBatch(progress, std::span<const Particle>(wave.particles).subspan(before));
      }
      if (!start_stop_) start_stop_ = WallTimeOrInterrupt(wave);
    }
    if (!start_stop_ && wave.particles.empty()) {
      start_stop_ = Stop({Termination::kTooManyFailures,
                          "every parameter of the finished run failed to simulate; last failure: " +
                              last_failure_});
    }
    wave.complete = !start_stop_;
    ComputeWaveStatistics(wave, options_.estimator);
    wave.wall_seconds = Seconds(wave_start);
    last_rate_ = 1.0;
    if (observer_) observer_->OnWaveEnd(wave);
    return wave;
  }

  // StartPopulation::expected against parameter i's re-simulated distances.
  void CheckResimulated(std::span<const double> expected,
                        std::span<const double> got,
                        std::size_t i) const {
    for (std::size_t k = 0; k < expected.size() && k < got.size(); ++k) {
      if (std::isnan(expected[k]) ||
          std::abs(got[k] - expected[k]) <= 1e-9 * std::max(1.0, std::abs(expected[k]))) {
        continue;
      }
      char text[160];
      std::snprintf(text,
                    sizeof text,
                    "parameter %zu re-simulates to distance %.10g for component \"%s\", where the "
                    "finished run had %.10g",
                    i,
                    got[k],
                    components_[k].name.c_str(),
                    expected[k]);
      throw Error(ErrorKind::kConfig,
                  std::string(text) + ": the model or that experiment's data changed",
                  "",
                  0,
                  "SmcProblem::start");
    }
  }

  // m_k per schedule slot of the wave after `waves`: the best likelihood distance among their
  // particles (as Thresholds computes it), 0 for threshold slots and before any particle.
  std::vector<double> OffsetsAfter(std::span<const WaveRecord> waves) const {
    std::vector<double> offsets(schedules_.size(), 0.0);
    for (std::size_t s = 0; s < schedules_.size(); ++s) {
      if (!IsLikelihood(s)) continue;
      const std::size_t k = threshold_components_[s];
      double best = std::numeric_limits<double>::infinity();
      for (const auto& w : waves) {
        for (const auto& p : w.particles) best = std::min(best, p.distance[k]);
      }
      if (std::isfinite(best)) offsets[s] = best;
    }
    return offsets;
  }

  // Wave t as a resample-move wave (docs/algorithm.md, "Resample-move"), when the run moves and
  // wave t - 1 (`previous`, done's last) is complete: its thresholds, the previous particles'
  // weights under them (move_weights_), the kernel fitted to those (proposal_) and the moves
  // (moves_). The thresholds are the schedule's, or a shorter step toward them (Del Moral, Doucet
  // & Jasra 2012) where the full step would leave fewer than MoveOptions::ess_fraction of the
  // previous effective sample size: for a likelihood component a step in 1 / T, for a threshold
  // one in the quantile of the previous distances it keeps. Nothing (a rejection wave instead)
  // when even that keeps fewer than MoveOptions::min_survivor_fraction x n_t.
  std::optional<WaveRecord> StartMoveWave(int t,
                                          const WaveRecord* previous,
                                          const std::vector<WaveRecord>& done) {
    if (options_.method != SamplerMethod::kResampleMove || !previous || !previous->complete ||
        previous->particles.empty() || RefreshAfter(*previous)) {
      return std::nullopt;
    }
    const std::span<const WaveRecord> earlier(done.data(), done.size() - 1);
    std::vector<double> offsets;
    // The full step: a list schedule's next value; an adaptive schedule's target, from which the
    // ESS rule below steps back (Del Moral, Doucet & Jasra 2012 choose eps_t by the ESS alone).
    std::vector<double> full = Thresholds(t, previous, earlier, offsets);
    for (std::size_t s = 0; s < schedules_.size(); ++s) {
      if (schedules_[s].kind != ThresholdKind::kList) full[s] = schedules_[s].target;
    }
    const std::vector<double> last_offsets = OffsetsAfter(earlier);
    const auto& particles = previous->particles;
    const std::size_t n_prev = particles.size();
    std::vector<double> before(n_prev);
    std::vector<double> last_log_accept(n_prev);
    for (std::size_t i = 0; i < n_prev; ++i) {
      before[i] = std::max(particles[i].weight, 0.0);
      // A move wave's (or a started run's wave 0's) target has no offsets; a rejection wave's
      // particles were accepted with LogAcceptance.
      last_log_accept[i] =
          previous->moves || (start_population_ && previous->wave == 0)
              ? LogTarget(particles[i].distance, previous->thresholds)
              : LogAcceptance(particles[i].distance, previous->thresholds, last_offsets);
    }
    // Per threshold slot: the weighted share of the previous particles within the full step's
    // threshold, and their distances.
    std::vector<std::vector<double>> column(schedules_.size());
    std::vector<double> kept_share(schedules_.size(), 1.0);
    for (std::size_t s = 0; s < schedules_.size(); ++s) {
      if (IsLikelihood(s)) continue;
      const std::size_t k = threshold_components_[s];
      double within = 0.0;
      double total = 0.0;
      for (std::size_t i = 0; i < n_prev; ++i) {
        column[s].push_back(particles[i].distance[k]);
        total += before[i];
        if (particles[i].distance[k] <= full[s]) within += before[i];
      }
      kept_share[s] = total > 0.0 ? within / total : 1.0;
    }
    auto thresholds_at = [&](double step) {
      if (step >= 1.0) return full;
      std::vector<double> eps(full.size());
      for (std::size_t s = 0; s < full.size(); ++s) {
        if (IsLikelihood(s)) {
          const double inverse = 1.0 / previous->thresholds[s] +
                                 step * (1.0 / full[s] - 1.0 / previous->thresholds[s]);
          eps[s] = inverse > 0.0 ? 1.0 / inverse : std::numeric_limits<double>::infinity();
        } else {
          const double level = 1.0 - step * (1.0 - kept_share[s]);
          eps[s] = std::max(full[s], WeightedQuantile(column[s], before, level));
        }
      }
      return eps;
    };
    auto weights_at = [&](double step) {
      const std::vector<double> eps = thresholds_at(step);
      std::vector<double> w(n_prev, 0.0);
      for (std::size_t i = 0; i < n_prev; ++i) {
        const double log_accept = LogTarget(particles[i].distance, eps);
        if (before[i] > 0.0 && log_accept > -std::numeric_limits<double>::infinity() &&
            last_log_accept[i] > -std::numeric_limits<double>::infinity()) {
          w[i] = before[i] * std::exp(log_accept - last_log_accept[i]);
        }
      }
      return w;
    };
    const MoveOptions& mo = options_.moves;
    const EssStep found = StepKeepingEss(weights_at, mo.ess_fraction * EffectiveSampleSize(before));
    // Distances tied at the step's threshold: the step that keeps enough changes nothing, so the
    // wave takes the smallest one that does (keeping less), judged below.
    const double step =
        thresholds_at(found.keeps) == previous->thresholds ? found.loses : found.keeps;
    std::vector<double> weights = weights_at(step);
    const double survivor_ess = EffectiveSampleSize(weights);
    const int n = options_.AcceptedIn(t);
    if (survivor_ess < mo.min_survivor_fraction * n) return std::nullopt;

    WaveRecord wave;
    wave.wave = t;
    wave.thresholds = thresholds_at(step);
    offsets_ = offsets;
    wave.phi = options_.tempering.Phi(t, options_.num_waves);
    // The reweighted particles, as the kernels and the local moves see them.
    Population population;
    population.num_free_bits = static_cast<std::size_t>(space_.num_free_bits());
    population.num_reals = static_cast<std::size_t>(space_.num_reals());
    double total = 0.0;
    for (double w : weights) total += w;
    for (std::size_t i = 0; i < n_prev; ++i) {
      if (!(weights[i] > 0.0)) continue;
      const auto& p = particles[i];
      const std::size_t row = population.free_bits.size();
      population.free_bits.resize(row + population.num_free_bits);
      COMBABC_CHECK(space_.binary().Reduce(
          p.theta.bits, std::span(population.free_bits.data() + row, population.num_free_bits)));
      population.reals.insert(population.reals.end(), p.theta.reals.begin(), p.theta.reals.end());
      population.weights.push_back(weights[i] / total);
      population.within_next.push_back(1);
      ++population.size;
    }
    proposal_ = kernel_->Fit(population, space_, Tempering{wave.phi, options_.tempering.form});
    from_prior_ = false;
    // The ancestor kernel beside the configured one (unless it is the configured one).
    ancestor_proposal_.reset();
    if (kernel_->name() != ToString(BinaryKernelKind::kAncestor)) {
      ancestor_proposal_ =
          AncestorKernel().Fit(population, space_, Tempering{wave.phi, options_.tempering.form});
    }
    moves_ = std::make_unique<MoveProposals>(
        population, space_, proposal_.get(), ancestor_proposal_.get(), mo.independent_share);
    move_weights_ = std::move(weights);
    wave.proposal = proposal_->Marginals();
    wave.moves = WaveMoves{.survivor_ess = survivor_ess, .step = step};
    if (observer_) observer_->OnWaveStart(wave);
    return wave;
  }

  // The ancestor kernel (docs/algorithm.md, "Joint: ancestor"), whatever the configured one: the
  // moves' second independent proposal and the final independent wave's.
  const JointKernel& AncestorKernel() {
    if (kernel_->name() == ToString(BinaryKernelKind::kAncestor)) return *kernel_;
    if (!ancestor_kernel_) {
      ProposalOptions ancestor = options_.proposal;
      ancestor.binary = BinaryKernelKind::kAncestor;
      ancestor.continuous = ContinuousKernelKind::kNormal;
      ancestor_kernel_ = MakeJointKernel(ancestor, space_);
    }
    return *ancestor_kernel_;
  }

  // The random streams of a move wave t's round r (r >= 1; r = kResampleRound for its
  // resampling): apart from every wave's own candidate streams, which are numbered by the wave
  // alone. `simulation` marks the streams its simulators draw from (one per simulated proposal).
  static constexpr std::uint64_t kResampleRound = 0xFFFFFFFFULL;
  static constexpr std::uint64_t kStartRound = 0xFFFFFFFEULL;  // SmcProblem::start's wave 0
  static std::uint64_t MoveStream(int t, std::uint64_t round, bool simulation) {
    return (simulation ? 1ULL << 63 : 0ULL) | (round << 32) | static_cast<std::uint64_t>(t);
  }

  // Resamples n_t of the previous wave's particles by their move_weights_ and moves each by
  // Metropolis-Hastings steps that leave the wave's target p(theta) A(d) invariant, A the
  // acceptance of Accept (an indicator for thresholds, exp(-(d - m) / T) for a likelihood: a
  // pseudo-marginal ratio where the simulator is stochastic, Andrieu & Roberts 2009). Rounds go
  // on until a particle has moved with probability 1 - stay_probability (RoundsNeeded).
  // The chains a move wave starts from: n_t of the previous wave's particles resampled by their
  // move_weights_ (wave.particles), with each one's free bits, reals, log target and log prior.
  struct MoveChains {
    std::vector<std::uint8_t> free;
    std::vector<double> reals;
    std::vector<double> log_accept;
    std::vector<double> log_prior;
  };
  MoveChains ResampleChains(WaveRecord& wave, const WaveRecord& previous, std::size_t nz) const {
    const std::size_t f = static_cast<std::size_t>(space_.num_free_bits());
    const std::size_t r = static_cast<std::size_t>(space_.num_reals());
    RandomStream resample(options_.seed, MoveStream(wave.wave, kResampleRound, false), 0);
    const auto picked = SystematicResample(move_weights_, nz, resample.Uniform());
    MoveChains c{std::vector<std::uint8_t>(nz * f),
                 std::vector<double>(nz * r),
                 std::vector<double>(nz),
                 std::vector<double>(nz)};
    wave.particles.reserve(nz);
    for (std::size_t i = 0; i < nz; ++i) {
      Particle p = previous.particles[picked[i]];
      p.eve = previous.moves ? p.eve : p.index;
      p.ancestor = p.index;
      p.index = static_cast<std::int64_t>(i);
      p.log_weight = 0.0;
      p.multiplier = 1.0;
      auto fi = std::span(c.free.data() + i * f, f);
      COMBABC_CHECK(space_.binary().Reduce(p.theta.bits, fi));
      std::copy(p.theta.reals.begin(), p.theta.reals.end(), c.reals.begin() + i * r);
      c.log_accept[i] = LogTarget(p.distance, wave.thresholds);
      c.log_prior[i] =
          space_.LogPriorBits(fi) + (r > 0 ? space_.LogPriorReals(p.theta.reals) : 0.0);
      wave.particles.push_back(std::move(p));
    }
    return c;
  }

  // The observer's view of a move round's batch (its failures: those since failures_before).
  void ReportMoveBatch(const WaveRecord& wave, std::size_t failures_before, int n) const {
    if (!observer_) return;
    BatchProgress progress{
        wave.wave,
        wave.candidates,
        0,
        0,
        n,
        total_,
        Seconds(start_),
        static_cast<std::int64_t>(wave.failures.size()),
        std::span<const SimulationFailure>(wave.failures).subspan(failures_before),
        std::nullopt};
    observer_->OnBatch(progress, {});
  }

  Stop MoveWave(WaveRecord& wave, const WaveRecord& previous) {
    const auto wave_start = Clock::now();
    const int n = options_.AcceptedIn(wave.wave);
    const auto nz = static_cast<std::size_t>(n);
    const std::size_t f = static_cast<std::size_t>(space_.num_free_bits());
    const std::size_t r = static_cast<std::size_t>(space_.num_reals());
    WaveMoves& moves = *wave.moves;
    MoveChains chains = ResampleChains(wave, previous, nz);
    auto& [free, reals, log_accept, log_prior] = chains;
    CandidateBatch batch(space_, simulator_, distance_, components_.size());
    std::vector<std::uint8_t> new_free(nz * f);
    std::vector<double> new_reals(nz * r);
    std::vector<std::uint8_t> given_free;
    std::vector<double> given_reals;
    std::vector<MoveProposal> proposed(nz);
    std::vector<double> uniforms(nz);
    std::vector<std::size_t> simulated;
    Stop stop;
    int rounds = options_.moves.max_rounds;
    for (int round = 1; round <= rounds && !stop; ++round) {
      simulated.clear();
      given_free.clear();
      given_reals.clear();
      for (std::size_t i = 0; i < nz; ++i) {
        RandomStream rng(options_.seed, MoveStream(wave.wave, round, false), i);
        const auto nf = std::span(new_free.data() + i * f, f);
        const auto nr = std::span(new_reals.data() + i * r, r);
        proposed[i] = moves_->Propose(rng,
                                      std::span<const std::uint8_t>(free.data() + i * f, f),
                                      std::span<const double>(reals.data() + i * r, r),
                                      nf,
                                      nr);
        uniforms[i] = rng.Uniform();
        ++moves.proposed;
        moves.independent_proposed += proposed[i].independent ? 1 : 0;
        if (proposed[i].outside_prior) continue;  // rejected without a simulation
        simulated.push_back(i);
        given_free.insert(given_free.end(), nf.begin(), nf.end());
        given_reals.insert(given_reals.end(), nr.begin(), nr.end());
      }
      WaveProposal given{.given_free = given_free,
                         .given_reals = given_reals,
                         .given = true,
                         .stream = MoveStream(wave.wave, static_cast<std::uint64_t>(round), true)};
      const auto count = static_cast<std::int64_t>(simulated.size());
      std::int64_t next = 0;
      while (next < count) {
        std::int64_t size = std::min(count - next, MoveBatchSize());
        if (options_.max_simulations > 0) size = std::min(size, options_.max_simulations - total_);
        if (size <= 0) {
          stop = Stop({Termination::kBudgetExhausted, BudgetMessage(options_, wave.wave)});
          break;
        }
        const auto batch_start = Clock::now();
        batch.Evaluate(*executor_, options_.seed, wave.wave, next, size, given);
        MeasureCost(size, Seconds(batch_start));
        const std::size_t failures_before = wave.failures.size();
        for (std::int64_t j = 0; j < size; ++j) {
          const std::size_t i = simulated[static_cast<std::size_t>(next + j)];
          ++total_;
          const std::int64_t candidate = wave.candidates++;
          if (batch.failed(j)) {
            wave.failures.push_back({candidate, std::string(batch.reason(j))});
            ++failures_;
            last_failure_ = Describe(wave.wave, wave.failures.back());
          } else {
            const auto nf = std::span<const std::uint8_t>(new_free.data() + i * f, f);
            const auto nr = std::span<const double>(new_reals.data() + i * r, r);
            const double new_accept = LogTarget(batch.distance(j), wave.thresholds);
            const double new_prior =
                space_.LogPriorBits(nf) + (r > 0 ? space_.LogPriorReals(nr) : 0.0);
            const double log_ratio =
                new_prior - log_prior[i] + new_accept - log_accept[i] + proposed[i].log_q_ratio;
            if (new_accept > -std::numeric_limits<double>::infinity() &&
                std::log(uniforms[i]) < log_ratio) {
              Particle moved =
                  batch.MakeParticle(j, static_cast<std::int64_t>(i), options_.keep_outputs);
              moved.log_weight = 0.0;
              moved.ancestor = wave.particles[i].ancestor;
              moved.eve = wave.particles[i].eve;
              wave.particles[i] = std::move(moved);
              std::copy(nf.begin(), nf.end(), free.begin() + i * f);
              std::copy(nr.begin(), nr.end(), reals.begin() + i * r);
              log_accept[i] = new_accept;
              log_prior[i] = new_prior;
              ++moves.accepted;
              moves.independent_accepted += proposed[i].independent ? 1 : 0;
            }
          }
          stop = FailureOrFloorStop(
              options_, total_, failures_, last_failure_, wave.wave, wave.candidates, n);
          if (stop) break;
        }
        next += size;
        ReportMoveBatch(wave, failures_before, n);
        if (stop) break;
        stop = WallTimeOrInterrupt(wave);
        if (stop) break;
      }
      if (stop) break;
      moves.rounds = round;
      const double rate = static_cast<double>(moves.accepted) /
                          static_cast<double>(std::max<std::int64_t>(moves.proposed, 1));
      rounds = std::max(
          round, RoundsNeeded(rate, options_.moves.stay_probability, options_.moves.max_rounds));
    }
    wave.complete = !stop;
    // An unfinished move wave holds no posterior: a resumed run does it again.
    if (!wave.complete) wave.particles.clear();
    ComputeWaveStatistics(wave, options_.estimator);
    wave.acceptance_rate = moves.proposed > 0 ? static_cast<double>(moves.accepted) /
                                                    static_cast<double>(moves.proposed)
                                              : 0.0;
    wave.wall_seconds = Seconds(wave_start);
    last_rate_ = wave.acceptance_rate;
    if (observer_) observer_->OnWaveEnd(wave);
    return stop;
  }

  // Simulations per batch of a move round: at most kMaxBatchSeconds of work per worker (so that a
  // slow simulator's run shows progress and stops on Ctrl-C often), one per worker until the
  // cost is known. The history does not depend on it: every proposal is decided in index order.
  std::int64_t MoveBatchSize() const {
    if (options_.batch_size > 0) return options_.batch_size;
    const std::int64_t workers = executor_->concurrency();
    if (!(cost_s_ > 0.0)) return workers;
    return workers * static_cast<std::int64_t>(
                         std::clamp(std::ceil(kMaxBatchSeconds / cost_s_), 1.0, 4096.0));
  }

  // The wall-time limit or an interrupt, decided by the primary between batches.
  Stop WallTimeOrInterrupt(const WaveRecord& wave) const {
    if (executor_->FromPrimary(options_.max_wall_time_s > 0 &&
                               Seconds(start_) >= options_.max_wall_time_s)) {
      return Stop({Termination::kWallTimeExceeded,
                   "wall-time limit reached in wave " + std::to_string(wave.wave + 1)});
    }
    if (executor_->FromPrimary(observer_ && observer_->ShouldStop())) {
      return Stop(
          {Termination::kInterrupted, "interrupted in wave " + std::to_string(wave.wave + 1)});
    }
    return std::nullopt;
  }

  // The expensive-to-cheap cost ratio: the options' when set, else measured over the waves
  // `done` and `wave` (summed call seconds per simulation); 0 when it cannot be measured yet.
  double CostRatio(const WaveRecord& wave, std::span<const WaveRecord> done) const {
    if (options_.multi_fidelity.cost_ratio > 0.0) return options_.multi_fidelity.cost_ratio;
    double cheap_seconds = 0.0;
    double expensive_seconds = 0.0;
    double cheap = 0.0;
    double expensive = 0.0;
    auto add = [&](const WaveRecord& w) {
      if (!w.multi_fidelity) return;
      cheap_seconds += w.multi_fidelity->cheap_seconds;
      expensive_seconds += w.multi_fidelity->expensive_seconds;
      cheap += static_cast<double>(w.candidates);
      expensive += static_cast<double>(w.multi_fidelity->expensive_simulations);
    };
    for (const auto& w : done) add(w);
    add(wave);
    const double ratio = (expensive_seconds / expensive) / (cheap_seconds / cheap);
    return std::isfinite(ratio) && ratio > 0.0 ? ratio : 0.0;
  }

  // Sets wave.multi_fidelity's cost ratio and the continuation probabilities of the next wave
  // (docs/algorithm.md, "Multi-fidelity sampling"): with adapt, for a complete wave whose cost
  // ratio is known, Prescott & Baker's optimum estimated from this wave's particles classified
  // by the next wave's thresholds; else the options' fixed probabilities.
  void ChooseNextContinuation(WaveRecord& wave, std::span<const WaveRecord> done) const {
    auto& fidelity = *wave.multi_fidelity;
    const auto& mf = options_.multi_fidelity;
    fidelity.cost_ratio = CostRatio(wave, done);
    fidelity.next_continue_if_accepted =
        mf.adapt ? fidelity.continue_if_accepted : mf.continue_if_accepted;
    fidelity.next_continue_if_rejected =
        mf.adapt ? fidelity.continue_if_rejected : mf.continue_if_rejected;
    const auto candidates = wave.candidates - static_cast<std::int64_t>(wave.failures.size());
    // No next wave (the last, or the target reached): nothing to tune for.
    const bool last = wave.wave + 1 >= options_.num_waves || AllFinal(wave);
    // Nothing confirmed (a wave of infinite thresholds): no error of the cheap model was seen,
    // nothing to tune from.
    if (!mf.adapt || !wave.complete || last || !(fidelity.cost_ratio > 0.0) || candidates <= 0 ||
        fidelity.expensive_simulations == 0) {
      return;
    }
    // The next wave's thresholds, exactly as StartWave will compute them.
    std::vector<double> offsets;
    const auto eps = Thresholds(wave.wave + 1, &wave, done, offsets);
    ContinuationStatistics statistics;
    statistics.cost_ratio = fidelity.cost_ratio;
    double max_lw = -INFINITY;
    for (const auto& p : wave.particles) max_lw = std::max(max_lw, p.log_weight);
    double cheap_accepted = 0.0;
    for (const auto& p : wave.particles) {
      // The paper's eq. 17 with q = this wave's proposal: w = p / q, outcomes by the next
      // thresholds, an outcome's indicator replaced by its probability over the acceptance
      // uniform (the two models share it), a confirmed particle counted 1 / alpha times.
      const double w = std::exp(p.log_weight - max_lw);
      const double cheap = AcceptanceProbability(p.low_distance, eps, offsets);
      cheap_accepted += cheap;
      statistics.w += w * w * cheap;
      if (!p.confirmed) continue;
      const double expensive = AcceptanceProbability(p.distance, eps, offsets);
      const double inverse_alpha = InverseContinuation(p, wave);
      statistics.w += w * w * (expensive - cheap) * inverse_alpha;
      statistics.w_false_positive += w * w * std::max(cheap - expensive, 0.0) * inverse_alpha;
      statistics.w_false_negative += w * w * std::max(expensive - cheap, 0.0) * inverse_alpha;
    }
    // The false positives that weigh 0 are no particles (eta_1 = 1): counted as still accepted
    // by the cheap model and rejected by the expensive one at the next thresholds, an upper
    // bound that errs toward confirming more (they add nothing to W: their expensive outcome
    // is a rejection).
    const auto& unkept = *wave.multi_fidelity;
    cheap_accepted += static_cast<double>(unkept.unkept_false_positives);
    statistics.w_false_positive += std::exp(unkept.unkept_false_positive_log_w2 - 2.0 * max_lw);
    statistics.cheap_accepted = std::min(cheap_accepted / static_cast<double>(candidates), 1.0);
    const auto eta = OptimalContinuation(statistics, mf.floor);
    // The tuning lowers an eta only on the evidence of at least kMinConfirmations confirmed
    // candidates of its class, classed as the tuning classes them, by the next wave's thresholds
    // (a wave of infinite thresholds would count every confirmation as a cheap acceptance):
    // from fewer, "no error seen" is no evidence, and an eta sent to the floor on it would
    // rarely confirm again, leaving the cheap model's errors in place with weights that show no
    // spread. On the sensor example the default floor (0.1) is what kept every seed right; this
    // guard keeps the tuning from acting on a handful (docs/algorithm.md, "Tuning").
    std::int64_t accepted_confirmed = unkept.unkept_false_positives;
    for (const auto& p : wave.particles) {
      if (p.confirmed && AcceptanceProbability(p.low_distance, eps, offsets) > 0.5) {
        ++accepted_confirmed;
      }
    }
    const std::int64_t rejected_confirmed =
        std::max<std::int64_t>(fidelity.expensive_simulations - accepted_confirmed, 0);
    fidelity.next_continue_if_accepted =
        accepted_confirmed >= kMinConfirmations
            ? eta.continue_if_accepted
            : std::max(eta.continue_if_accepted, fidelity.continue_if_accepted);
    fidelity.next_continue_if_rejected =
        rejected_confirmed >= kMinConfirmations
            ? eta.continue_if_rejected
            : std::max(eta.continue_if_rejected, fidelity.continue_if_rejected);
  }

  // Every threshold of the wave is infinite (the first wave of an adaptive schedule).
  static bool InfiniteThresholds(const WaveRecord& wave) {
    return std::all_of(wave.thresholds.begin(), wave.thresholds.end(), [](double e) {
      return e == std::numeric_limits<double>::infinity();
    });
  }

  // 1 / the probability with which confirmed particle p of `wave` continued: eta_1 if the cheap
  // model accepted it, eta_2 if not. Its multiplier tells (1 - 1 / eta_1 < 0: a false positive;
  // 1: accepted by both; 1 / eta_2: a false negative) unless eta_2 = 1, where both acceptances
  // give 1: then the cheap distance's acceptance probability at the wave's thresholds weighs
  // the two (exact for threshold components; the uniform of a likelihood one is not stored).
  double InverseContinuation(const Particle& p, const WaveRecord& wave) const {
    const double eta_1 = wave.multi_fidelity->continue_if_accepted;
    const double eta_2 = wave.multi_fidelity->continue_if_rejected;
    if (InfiniteThresholds(wave)) return 1.0 / eta_2;  // every candidate continued with eta_2
    if (p.multiplier < 0.0 || eta_1 == eta_2) return 1.0 / eta_1;
    if (eta_2 != 1.0) return p.multiplier == 1.0 ? 1.0 / eta_1 : 1.0 / eta_2;
    const double accepted = AcceptanceProbability(p.low_distance, wave.thresholds, offsets_);
    return accepted / eta_1 + (1.0 - accepted) / eta_2;
  }

  RunHistory Finish(RunHistory history, Termination termination, std::string message) {
    auto& s = history.summary;
    s.termination = termination;
    s.message = std::move(message);
    s.waves_completed = 0;
    s.simulations = 0;
    s.failures = 0;
    for (const auto& w : history.waves) {
      s.waves_completed += w.complete;
      s.simulations += w.candidates;
      s.failures += static_cast<std::int64_t>(w.failures.size());
    }
    s.simulations_discarded = discarded_;
    s.wall_seconds = Seconds(start_);
    return history;
  }

  const ParameterSpace& space_;
  const Simulator& simulator_;
  const Simulator* low_fidelity_;            // null: single fidelity
  const StartPopulation* start_population_;  // null: wave 0 from the prior
  Stop start_stop_;                          // what stopped wave 0 from start_, if anything
  const Distance& distance_;
  const SmcOptions& options_;
  SmcObserver* observer_;
  const JointKernel* kernel_ = nullptr;
  Executor* executor_ = nullptr;
  std::unique_ptr<JointKernel> owned_kernel_;
  std::unique_ptr<Executor> owned_executor_;
  // The current wave's proposal.
  std::unique_ptr<JointProposal> proposal_;
  bool from_prior_ = true;
  // A move wave's local and independent proposals, and the previous particles' weights under its
  // target (what it resamples by).
  std::unique_ptr<MoveProposals> moves_;
  std::unique_ptr<JointKernel> ancestor_kernel_;
  std::unique_ptr<JointProposal> ancestor_proposal_;
  std::vector<double> move_weights_;
  std::vector<DistanceComponent> components_;
  std::vector<std::size_t> threshold_components_;
  std::vector<ThresholdSchedule> schedules_;
  bool stochastic_ = false;      // some component is a negative log-likelihood
  std::vector<double> offsets_;  // m_k per schedule slot for the current wave (0: thresholds)
  Clock::time_point start_;
  std::int64_t total_ = 0;
  std::int64_t discarded_ = 0;
  std::int64_t failures_ = 0;  // failed simulations among total_
  std::string last_failure_;   // the latest of them, described for the stop message
  double last_rate_ = 1.0;
  double cost_s_ = 0.0;  // seconds a worker spends per candidate, the last batch's; 0 = unknown
};

void CheckProblem(const SmcProblem& problem) {
  if (!problem.space || !problem.simulator || !problem.distance) {
    throw Error(
        ErrorKind::kConfig, "space, simulator and distance must all be set", "", 0, "SmcProblem");
  }
}

}  // namespace

RunHistory RunCombinatorialSmc(const SmcProblem& problem,
                               const SmcOptions& options,
                               SmcObserver* observer,
                               const ResumePoint* resume) {
  CheckProblem(problem);
  std::string why;
  if (!options.IsValid(&why)) throw Error(ErrorKind::kConfig, why);
  SmcRun run(problem, options, observer);
  return run.Run(resume);
}

std::optional<std::pair<Termination, std::string>> ImmediateStop(const SmcOptions& options,
                                                                 const ResumePoint& resume) {
  std::int64_t total = 0;
  std::int64_t failures = 0;
  std::string last_failure;
  for (const auto& w : resume.completed) {
    total += w.candidates;
    failures += static_cast<std::int64_t>(w.failures.size());
    if (!w.failures.empty()) last_failure = Describe(w.wave, w.failures.back());
  }
  const int wave =
      resume.has_partial ? resume.partial_wave : static_cast<int>(resume.completed.size());
  const std::int64_t candidates = resume.has_partial ? resume.partial_next_index : 0;
  total += candidates;
  if (resume.has_partial) {
    failures += static_cast<std::int64_t>(resume.partial_failures.size());
    if (!resume.partial_failures.empty()) {
      last_failure = Describe(wave, resume.partial_failures.back());
    }
  }
  if (options.max_simulations > 0 && total >= options.max_simulations) {
    return Stop({Termination::kBudgetExhausted, BudgetMessage(options, wave)});
  }
  const auto accepted =
      resume.has_partial ? static_cast<std::int64_t>(resume.partial_accepted.size()) : 0;
  return FailureOrFloorStop(options, total, failures, last_failure, wave, candidates, accepted);
}

RunHistory RunRejection(const SmcProblem& problem,
                        int accepted,
                        const std::vector<double>& thresholds,
                        std::uint64_t seed,
                        int threads,
                        std::int64_t max_simulations) {
  SmcOptions options;
  options.num_waves = 1;
  options.accepted_per_wave = accepted;
  options.seed = seed;
  options.threads = threads;
  options.max_simulations = max_simulations;
  for (double eps : thresholds) {
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = {eps};
    options.thresholds.push_back(s);
  }
  return RunCombinatorialSmc(problem, options);
}

}  // namespace combabc
