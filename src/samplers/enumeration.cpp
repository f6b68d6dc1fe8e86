// Exact ABC posterior by enumerating every free-bit configuration (docs/algorithm.md, "Exact
// enumeration").
#include "combabc/samplers/enumeration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/core/executor.hpp"

namespace combabc {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Configurations [first, first + n): decoded, expanded to bits, simulated and measured by an
// Executor into flat buffers reused batch after batch, so memory stays one batch whatever 2^k is.
class EnumerationBatch : public BatchTask {
 public:
  EnumerationBatch(const ParameterSpace& space,
                   const Simulator& simulator,
                   const Distance& distance,
                   std::size_t components,
                   std::uint64_t seed)
      : space_(space),
        simulator_(simulator),
        distance_(distance),
        seed_(seed),
        d_(static_cast<std::size_t>(space.num_bits())),
        f_(static_cast<std::size_t>(space.num_free_bits())),
        m_(static_cast<std::size_t>(simulator.output_size())),
        c_(components) {}

  void Evaluate(Executor& executor, std::int64_t first, std::int64_t count) {
    const auto n = static_cast<std::size_t>(count);
    first_ = first;
    free_.resize(n * f_);
    bits_.resize(n * d_);
    outputs_.resize(n * m_);
    distances_.resize(n * c_);
    log_prior_.resize(n);
    status_.assign(n, 0);
    reasons_.assign(n * kFailureReasonBytes, '\0');
    rngs_.resize(n, RandomStream(0, 0, 0));
    executor.Execute(n, *this);
  }

  std::span<const std::uint8_t> bits(std::size_t i) const { return {bits_.data() + i * d_, d_}; }
  std::span<const double> output(std::size_t i) const { return {outputs_.data() + i * m_, m_}; }
  std::span<const double> distance(std::size_t i) const { return {distances_.data() + i * c_, c_}; }
  double log_prior(std::size_t i) const { return log_prior_[i]; }

  void EvaluateRange(std::size_t begin, std::size_t end) override {
    const std::string which = "enumeration, configurations " +
                              std::to_string(first_ + static_cast<std::int64_t>(begin)) + "-" +
                              std::to_string(first_ + static_cast<std::int64_t>(end) - 1);
    for (std::size_t i = begin; i < end; ++i) {
      const auto index = static_cast<std::uint64_t>(first_) + i;
      std::span<std::uint8_t> free(free_.data() + i * f_, f_);
      for (std::size_t j = 0; j < f_; ++j) free[j] = static_cast<std::uint8_t>((index >> j) & 1U);
      space_.binary().Expand(free, std::span(bits_.data() + i * d_, d_));
      log_prior_[i] = space_.LogPriorBits(free);
      rngs_[i] = RandomStream(seed_, 0, index);
    }
    try {
      const ParameterBatch batch{
          end - begin,
          d_,
          0,
          std::span<const std::uint8_t>(bits_.data() + begin * d_, (end - begin) * d_),
          {}};
      BatchFailures failures =
          BatchFailures(std::span(status_), std::span(reasons_)).Sub(begin, end - begin);
      simulator_.SimulateBatch(batch,
                               std::span(rngs_.data() + begin, end - begin),
                               std::span(outputs_.data() + begin * m_, (end - begin) * m_),
                               failures);
    } catch (const std::exception& e) {
      throw Error(ErrorKind::kSoftware, std::string("simulator failed: ") + e.what(), "", 0, which);
    }
    // The exact posterior needs every configuration's distance: unlike a sampled run, an
    // enumeration cannot carry on past a failed simulation. The configurations before the first
    // failed one are measured (one call), and the first failure in index order ends the run.
    const BatchFailures all{std::span(status_), std::span(reasons_)};
    std::size_t measured = begin;
    while (measured < end && !all.failed(measured)) ++measured;
    BatchFailures failures = all.Sub(begin, measured - begin);
    try {
      distance_.EvaluateBatch(
          std::span<const double>(outputs_.data() + begin * m_, (measured - begin) * m_),
          std::span(distances_.data() + begin * c_, (measured - begin) * c_),
          failures);
    } catch (const std::exception& e) {
      throw Error(ErrorKind::kSoftware, std::string("distance failed: ") + e.what(), "", 0, which);
    }
    auto configuration = [&](std::size_t i) {
      return "enumeration, configuration " + std::to_string(first_ + static_cast<std::int64_t>(i));
    };
    for (std::size_t i = begin; i < end; ++i) {
      if (all.failed(i)) {
        throw Error(ErrorKind::kSoftware,
                    "simulation failed: " + std::string(all.reason(i)) +
                        " (an enumeration needs every configuration)",
                    "",
                    0,
                    configuration(i));
      }
      for (std::size_t k = 0; k < c_; ++k) {
        if (std::isnan(distance(i)[k])) {
          throw Error(ErrorKind::kSoftware,
                      "distance component " + std::to_string(k) +
                          " is NaN (the simulated output holds NaN or the distance is undefined)",
                      "",
                      0,
                      configuration(i));
        }
      }
    }
  }

  std::vector<Buffer> Results() override {
    return {{bits_.data(), d_},
            {outputs_.data(), m_ * sizeof(double)},
            {distances_.data(), c_ * sizeof(double)},
            {log_prior_.data(), sizeof(double)},
            {status_.data(), 1},
            {reasons_.data(), kFailureReasonBytes}};
  }

 private:
  const ParameterSpace& space_;
  const Simulator& simulator_;
  const Distance& distance_;
  std::uint64_t seed_;
  std::size_t d_, f_, m_, c_;
  std::int64_t first_ = 0;
  std::vector<std::uint8_t> free_, bits_, status_;
  std::vector<char> reasons_;
  std::vector<double> outputs_, distances_, log_prior_;
  std::vector<RandomStream> rngs_;
};

// Larger mass first; equal masses (a uniform prior makes them all equal) by configuration index,
// so which particles are kept never depends on the order they were found in.
bool Better(const Particle& a, const Particle& b) {
  return a.log_weight != b.log_weight ? a.log_weight > b.log_weight : a.index < b.index;
}

// The `capacity` best particles seen so far; front() is the worst of them (a heap under Better).
class Best {
 public:
  explicit Best(std::size_t capacity) : capacity_(capacity) {}
  bool WouldKeep(double log_weight, std::int64_t index) const {
    if (heap_.size() < capacity_) return true;
    if (capacity_ == 0) return false;
    Particle probe;
    probe.log_weight = log_weight;
    probe.index = index;
    return Better(probe, heap_.front());
  }
  void Add(Particle p) {
    if (heap_.size() == capacity_) {
      std::pop_heap(heap_.begin(), heap_.end(), Better);
      heap_.back() = std::move(p);
    } else {
      heap_.push_back(std::move(p));
    }
    std::push_heap(heap_.begin(), heap_.end(), Better);
  }
  std::vector<Particle> Sorted() const {
    auto out = heap_;
    std::sort(out.begin(), out.end(), Better);
    return out;
  }

 private:
  std::size_t capacity_;
  std::vector<Particle> heap_;
};

void CheckOptions(const SmcProblem& problem,
                  const EnumerationOptions& options,
                  const std::vector<DistanceComponent>& components) {
  if (!problem.space || !problem.simulator || !problem.distance) {
    throw Error(
        ErrorKind::kConfig, "space, simulator and distance must all be set", "", 0, "SmcProblem");
  }
  if (problem.space->num_reals() > 0) {
    throw Error(ErrorKind::kConfig,
                "enumeration needs a purely binary space; this one has " +
                    std::to_string(problem.space->num_reals()) + " continuous parameters",
                "",
                0,
                "SmcProblem::space");
  }
  const int free = problem.space->num_free_bits();
  if (free > kMaxEnumerationBits) {
    throw Error(ErrorKind::kConfig,
                "enumeration of " + std::to_string(free) + " free bits (2^" + std::to_string(free) +
                    " configurations) exceeds the limit of 2^" +
                    std::to_string(kMaxEnumerationBits) +
                    "; tie bits to reduce them, or run combinatorial ABC-SMC",
                "",
                0,
                "SmcProblem::space");
  }
  std::size_t threshold_components = 0;
  for (const auto& c : components) threshold_components += c.kind != ComponentKind::kIndicator;
  if (options.thresholds.size() != threshold_components) {
    throw Error(ErrorKind::kConfig,
                "has " + std::to_string(options.thresholds.size()) +
                    " thresholds; the distance has " + std::to_string(threshold_components) +
                    " threshold and likelihood components",
                "",
                0,
                "EnumerationOptions::thresholds");
  }
  for (double eps : options.thresholds) {
    if (!(eps >= 0.0)) {
      throw Error(ErrorKind::kConfig,
                  "must be >= 0 (got " + std::to_string(eps) + ")",
                  "",
                  0,
                  "EnumerationOptions::thresholds");
    }
  }
  if (options.batch_size < 1 || options.max_particles < 0 || options.top < 0 ||
      options.threads < 0) {
    throw Error(ErrorKind::kConfig,
                "batch_size must be >= 1; max_particles, top and threads >= 0",
                "",
                0,
                "EnumerationOptions");
  }
  if (problem.simulator->output_size() < 0) {
    throw Error(ErrorKind::kConfig, "simulator output_size() is negative");
  }
}

// The log of a configuration's likelihood at the thresholds: -inf where a threshold or
// indicator component rejects it, else -sum_k d_k / T_k over the likelihood components (the
// noise-aware posterior p(theta) exp(-d / T), docs/algorithm.md "Noise-aware acceptance").
double LogLikelihood(const std::vector<DistanceComponent>& components,
                     const std::vector<double>& thresholds,
                     std::span<const double> dist) {
  constexpr double kReject = -std::numeric_limits<double>::infinity();
  double log_l = 0.0;
  std::size_t s = 0;
  for (std::size_t k = 0; k < components.size(); ++k) {
    if (components[k].kind == ComponentKind::kThreshold) {
      if (!(dist[k] <= thresholds[s++])) return kReject;
    } else if (components[k].kind == ComponentKind::kNegLogLikelihood) {
      const double temperature = thresholds[s++];
      if (std::isinf(temperature)) continue;
      if (!(dist[k] < std::numeric_limits<double>::infinity())) return kReject;
      log_l -= dist[k] / temperature;
    } else if (dist[k] != components[k].required) {
      return kReject;
    }
  }
  return log_l;
}

// The top configurations and the kept particles, each weighted by its share of the mass (the top
// ones of all the mass, the kept ones of theirs), the kept ones in configuration order.
void KeepParticles(std::vector<Particle> sorted,
                   const EnumerationOptions& options,
                   double shift,
                   double mass_sum,
                   EnumerationResult& result) {
  const auto top = std::min(sorted.size(), static_cast<std::size_t>(options.top));
  result.top.assign(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(top));
  for (auto& p : result.top) p.weight = std::exp(p.log_weight - shift) / mass_sum;
  sorted.resize(std::min(sorted.size(), static_cast<std::size_t>(options.max_particles)));
  double kept_mass = 0.0;
  for (const auto& p : sorted) kept_mass += std::exp(p.log_weight - shift);
  for (auto& p : sorted) p.weight = std::exp(p.log_weight - shift) / kept_mass;
  std::sort(sorted.begin(), sorted.end(), [](const Particle& a, const Particle& b) {
    return a.index < b.index;
  });
  result.particles = std::move(sorted);
}

}  // namespace

WaveRecord EnumerationResult::Wave(const std::vector<double>& thresholds,
                                   const std::vector<double>& proposal) const {
  WaveRecord w;
  w.wave = 0;
  w.thresholds = thresholds;
  w.proposal = proposal;
  w.candidates = enumerated;
  w.accepted = accepted;
  w.acceptance_rate =
      enumerated > 0 ? static_cast<double>(accepted) / static_cast<double>(enumerated) : 0.0;
  w.complete = !interrupted;
  w.marginals_paper = marginals;
  w.marginals_importance = marginals;
  w.ess = ess;
  w.distinct = accepted;  // every configuration is enumerated once
  // Of the kept particles, as for any wave (and as a reloaded history recomputes them): the exact
  // `correlations` to round-off while no accepted configuration was dropped.
  w.pair_correlations = PairCorrelations(particles);
  w.wall_seconds = wall_seconds;
  w.particles = particles;
  return w;
}

EnumerationResult Enumerate(const SmcProblem& problem,
                            const EnumerationOptions& options,
                            SmcObserver* observer) {
  const auto start = Clock::now();
  const auto components =
      problem.distance ? problem.distance->components() : std::vector<DistanceComponent>{};
  CheckOptions(problem, options, components);
  const ParameterSpace& space = *problem.space;
  std::unique_ptr<Executor> owned_executor;
  Executor* executor = problem.executor;
  if (!executor) {
    owned_executor = std::make_unique<ThreadPoolExecutor>(options.threads);
    executor = owned_executor.get();
  }
  const auto d = static_cast<std::size_t>(space.num_bits());
  EnumerationResult result;
  result.configurations = std::int64_t{1} << space.num_free_bits();

  WaveRecord start_record;
  start_record.thresholds = options.thresholds;
  start_record.proposal = space.binary().free_prior_one();
  start_record.candidates = result.configurations;
  if (observer) observer->OnWaveStart(start_record);

  // Unnormalised sums, accumulated on this thread in configuration order: the same additions in
  // the same order for any executor, hence bit-identical results.
  BitMoments moments(d);
  double mass_sq_sum = 0.0;
  // Masses are exp(log mass - shift), shift the largest log mass so far (0 for a threshold-only
  // distance, whose masses are prior masses): a sharp likelihood's exp(-d) would underflow.
  double shift = 0.0;
  bool shifted = false;
  Best best(static_cast<std::size_t>(std::max(options.max_particles, options.top)));
  EnumerationBatch batch(
      space, *problem.simulator, *problem.distance, components.size(), options.seed);
  std::int64_t next = 0;
  while (next < result.configurations) {
    const std::int64_t n = std::min<std::int64_t>(options.batch_size, result.configurations - next);
    batch.Evaluate(*executor, next, n);
    for (std::int64_t i = 0; i < n; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const double log_l = LogLikelihood(components, options.thresholds, batch.distance(u));
      if (log_l == -std::numeric_limits<double>::infinity()) continue;
      const double log_prior = batch.log_prior(u) + log_l;
      // A configuration of prior mass 0 (a bit or tied group of prior 0 or 1 set the other way)
      // has no posterior mass: not counted as accepted, not listed (were only such accepted, the
      // weights below would divide by a zero evidence).
      if (log_prior == -std::numeric_limits<double>::infinity()) continue;
      ++result.accepted;
      if (log_l != 0.0 && (!shifted || log_prior > shift)) {
        const double factor = shifted ? std::exp(shift - log_prior) : 0.0;
        if (shifted) {
          moments.Scale(factor);
          mass_sq_sum *= factor * factor;
        }
        shift = log_prior;
        shifted = true;
      }
      const double mass = std::exp(log_prior - shift);
      mass_sq_sum += mass * mass;
      const auto bits = batch.bits(u);
      moments.Add(bits, mass);
      if (best.WouldKeep(log_prior, next + i)) {
        Particle p;
        p.index = next + i;
        p.theta.bits.assign(bits.begin(), bits.end());
        p.log_weight = log_prior;
        const auto dist = batch.distance(u);
        p.distance.assign(dist.begin(), dist.end());
        if (options.keep_outputs) {
          const auto out = batch.output(u);
          p.output.assign(out.begin(), out.end());
        }
        best.Add(std::move(p));
      }
    }
    next += n;
    result.enumerated = next;
    if (observer) {
      const BatchProgress progress{
          0, next, result.accepted, 0, 0, next, SecondsSince(start), 0, {}, std::nullopt};
      observer->OnBatch(progress, {});
    }
    // The primary's signals decide, so that every worker of a distributed executor stops alike.
    if (next < result.configurations && executor->FromPrimary(observer && observer->ShouldStop())) {
      result.interrupted = true;
      break;
    }
  }

  const double mass_sum = moments.total();
  result.evidence = mass_sum * std::exp(shift);
  if (result.accepted > 0) {
    result.marginals = moments.Marginals();
    result.correlations = moments.Correlations();
    result.ess = mass_sum * mass_sum / mass_sq_sum;
  }
  KeepParticles(best.Sorted(), options, shift, mass_sum, result);
  result.wall_seconds = SecondsSince(start);
  if (observer) observer->OnWaveEnd(result.Wave(options.thresholds, start_record.proposal));
  return result;
}

}  // namespace combabc
