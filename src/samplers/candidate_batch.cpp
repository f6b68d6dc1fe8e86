#include "samplers/candidate_batch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "combabc/core/error.hpp"

namespace combabc {

CandidateBatch::CandidateBatch(const ParameterSpace& space,
                               const Simulator& simulator,
                               const Distance& distance,
                               std::size_t num_components,
                               bool draw_uniform,
                               const LowFidelityStage* low_fidelity)
    : space_(space),
      simulator_(simulator),
      distance_(distance),
      low_fidelity_(low_fidelity),
      d_(static_cast<std::size_t>(space.num_bits())),
      f_(static_cast<std::size_t>(space.num_free_bits())),
      r_(static_cast<std::size_t>(space.num_reals())),
      m_(static_cast<std::size_t>(simulator.output_size())),
      c_(num_components),
      draw_uniform_(draw_uniform) {}

void CandidateBatch::Evaluate(Executor& executor,
                              std::uint64_t seed,
                              int wave,
                              std::int64_t first,
                              std::int64_t count,
                              const WaveProposal& proposal) {
  const auto n = static_cast<std::size_t>(count);
  free_.resize(n * f_);
  bits_.resize(n * d_);
  reals_.resize(n * r_);
  outputs_.resize(n * m_);
  distances_.resize(n * c_);
  low_distances_.assign(n * c_, std::numeric_limits<double>::quiet_NaN());
  fidelity_.assign(n, 0);
  seconds_.assign(n * 2, 0.0);
  log_weights_.resize(n);
  uniforms_.resize(n);
  status_.assign(n, 0);
  reasons_.assign(n * kFailureReasonBytes, '\0');
  rngs_.resize(n, RandomStream(0, 0, 0));
  seed_ = seed;
  wave_ = wave;
  first_ = first;
  proposal_ = proposal;
  executor.Execute(n, *this);
}

std::vector<BatchTask::Buffer> CandidateBatch::Results() {
  return {{bits_.data(), d_},
          {reals_.data(), r_ * sizeof(double)},
          {outputs_.data(), m_ * sizeof(double)},
          {distances_.data(), c_ * sizeof(double)},
          {log_weights_.data(), sizeof(double)},
          {uniforms_.data(), sizeof(double)},
          {status_.data(), 1},
          {reasons_.data(), kFailureReasonBytes},
          // Multi-fidelity only: without a low-fidelity stage they hold nothing to gather.
          {low_distances_.data(), low_fidelity_ ? c_ * sizeof(double) : 0},
          {fidelity_.data(), low_fidelity_ ? 1U : 0U},
          {seconds_.data(), low_fidelity_ ? 2 * sizeof(double) : 0}};
}

std::string_view CandidateBatch::reason(std::int64_t i) const {
  const char* row = reasons_.data() + static_cast<std::size_t>(i) * kFailureReasonBytes;
  return {row, strnlen(row, kFailureReasonBytes)};
}

void CandidateBatch::Fail(std::size_t i, std::string_view reason) {
  if (status_[i] != 0) return;
  BatchFailures(std::span(status_), std::span(reasons_)).Fail(i, reason);
}

void CandidateBatch::EvaluateRange(std::size_t begin, std::size_t end) {
  auto span_of = [](auto& v, std::size_t i, std::size_t width) {
    return std::span(v.data() + i * width, width);
  };
  const int wave = wave_;
  const std::int64_t first = first_;
  const std::string which = "wave " + std::to_string(wave + 1) + ", candidates " +
                            std::to_string(first + static_cast<std::int64_t>(begin)) + "-" +
                            std::to_string(first + static_cast<std::int64_t>(end) - 1);
  for (std::size_t i = begin; i < end; ++i) {
    const auto index = static_cast<std::uint64_t>(first) + i;
    rngs_[i] = RandomStream(
        seed_, proposal_.given ? proposal_.stream : static_cast<std::uint64_t>(wave), index);
    auto free = span_of(free_, i, f_);
    auto reals = span_of(reals_, i, r_);
    if (proposal_.given) {
      std::copy_n(
          proposal_.given_free.begin() + static_cast<std::ptrdiff_t>(index * f_), f_, free.begin());
      std::copy_n(proposal_.given_reals.begin() + static_cast<std::ptrdiff_t>(index * r_),
                  r_,
                  reals.begin());
      space_.binary().Expand(free, span_of(bits_, i, d_));
      log_weights_[i] = 0.0;
      continue;
    }
    try {
      proposal_.proposal->Sample(rngs_[i], free, reals);
    } catch (const std::exception& e) {
      throw Error(ErrorKind::kSoftware, e.what(), "", 0, which);
    }
    space_.binary().Expand(free, span_of(bits_, i, d_));
    // Importance weight p(theta) / q(theta). Wave 0 proposes from the prior: exactly 1.
    double log_weight = 0.0;
    if (!proposal_.from_prior) {
      log_weight = space_.LogPriorBits(free);
      if (r_ > 0) log_weight += space_.LogPriorReals(reals);
      log_weight -= proposal_.proposal->LogDensity(free, reals);
    }
    log_weights_[i] = log_weight;
  }
  const std::size_t count = end - begin;
  const ParameterBatch batch{count,
                             d_,
                             r_,
                             std::span<const std::uint8_t>(bits_.data() + begin * d_, count * d_),
                             std::span<const double>(reals_.data() + begin * r_, count * r_)};
  auto failures = BatchFailures(std::span(status_), std::span(reasons_)).Sub(begin, count);
  // The cheap simulator first when there is one: every candidate runs it.
  const double seconds = SimulateAndMeasure(low_fidelity_ ? *low_fidelity_->simulator : simulator_,
                                            batch,
                                            std::span(rngs_.data() + begin, count),
                                            std::span(outputs_.data() + begin * m_, count * m_),
                                            std::span(distances_.data() + begin * c_, count * c_),
                                            failures,
                                            which);
  if (low_fidelity_) {
    for (std::size_t i = begin; i < end; ++i) {
      seconds_[i * 2] = seconds / static_cast<double>(count);
    }
  }
  for (std::size_t i = begin; i < end; ++i) {
    // After the simulator's draws, so that they do not depend on whether it is drawn.
    uniforms_[i] = draw_uniform_ ? rngs_[i].Uniform() : 0.0;
  }
  if (low_fidelity_) ContinueWithExpensive(begin, end, which);
}

double CandidateBatch::SimulateAndMeasure(const Simulator& simulator,
                                          const ParameterBatch& batch,
                                          std::span<RandomStream> rngs,
                                          std::span<double> outputs,
                                          std::span<double> distances,
                                          BatchFailures& failures,
                                          const std::string& which) const {
  const std::size_t n = batch.count;
  auto fail = [&](std::size_t i, std::string_view reason) {
    if (!failures.failed(i)) failures.Fail(i, reason);
  };
  const auto start = std::chrono::steady_clock::now();
  try {
    simulator.SimulateBatch(batch, rngs, outputs, failures);
  } catch (const std::exception& e) {
    // Not a SimulationFailed of one candidate (SimulateBatch handles those): a defect.
    throw Error(ErrorKind::kSoftware, std::string("simulator failed: ") + e.what(), "", 0, which);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t i = 0; i < n; ++i) {
    if (failures.failed(i)) continue;
    // A NaN output is the simulation's failure (a diverged solve, an unreadable value), not the
    // run's: the candidate is recorded as failed and the run goes on.
    const auto output = outputs.subspan(i * m_, m_);
    const auto nan =
        std::find_if(output.begin(), output.end(), [](double v) { return std::isnan(v); });
    if (nan != output.end()) {
      fail(i, "output holds NaN at index " + std::to_string(nan - output.begin()));
    }
  }
  // One call for the batch's candidates still standing (a distance written in Python pays per
  // call); it skips the failed ones and may fail some itself.
  try {
    distance_.EvaluateBatch(outputs, distances, failures);
  } catch (const std::exception& e) {
    throw Error(ErrorKind::kSoftware, std::string("distance failed: ") + e.what(), "", 0, which);
  }
  for (std::size_t i = 0; i < n; ++i) {
    auto out = distances.subspan(i * c_, c_);
    if (failures.failed(i)) {
      // Never accepted: no distance is kept from outputs the simulator did not produce or the
      // distance could not measure.
      std::fill(out.begin(), out.end(), std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    for (std::size_t k = 0; k < c_; ++k) {
      if (std::isnan(out[k])) {
        fail(i, "distance component " + std::to_string(k) + " is NaN");
        break;
      }
    }
  }
  return seconds;
}

void CandidateBatch::ContinueWithExpensive(std::size_t begin,
                                           std::size_t end,
                                           const std::string& which) {
  const MultiFidelityOptions& options = low_fidelity_->options;
  std::vector<std::size_t> continued;
  for (std::size_t i = begin; i < end; ++i) {
    std::copy_n(distances_.begin() + static_cast<std::ptrdiff_t>(i * c_),
                c_,
                low_distances_.begin() + static_cast<std::ptrdiff_t>(i * c_));
    // Drawn for every candidate, failed or not, after the acceptance uniform: the candidate's
    // own stream, so that whether it continues does not depend on threads or batches.
    const double v = rngs_[i].Uniform();
    fidelity_[i] = 0;
    if (status_[i] != 0) continue;
    const bool cheap_accepted =
        low_fidelity_->accept(distance(static_cast<std::int64_t>(i)), uniforms_[i]);
    const double eta = cheap_accepted && !low_fidelity_->infinite_thresholds
                           ? options.continue_if_accepted
                           : options.continue_if_rejected;
    const bool continues = v < eta;
    fidelity_[i] = (cheap_accepted ? kCheapAccepted : 0) | (continues ? kContinued : 0);
    if (continues) continued.push_back(i);
  }
  if (continued.empty()) return;
  // The continued candidates, gathered: the expensive simulator sees one dense batch, and each
  // candidate goes on drawing from its own stream.
  const std::size_t n = continued.size();
  std::vector<std::uint8_t> bits(n * d_), status(n, 0);
  std::vector<double> reals(n * r_), outputs(n * m_), distances(n * c_);
  std::vector<char> reasons(n * kFailureReasonBytes, '\0');
  std::vector<RandomStream> rngs;
  rngs.reserve(n);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = continued[j];
    std::copy_n(bits_.begin() + static_cast<std::ptrdiff_t>(i * d_),
                d_,
                bits.begin() + static_cast<std::ptrdiff_t>(j * d_));
    std::copy_n(reals_.begin() + static_cast<std::ptrdiff_t>(i * r_),
                r_,
                reals.begin() + static_cast<std::ptrdiff_t>(j * r_));
    rngs.push_back(rngs_[i]);
  }
  const ParameterBatch batch{n, d_, r_, bits, reals};
  auto failures = BatchFailures(std::span(status), std::span(reasons));
  const double seconds =
      SimulateAndMeasure(simulator_, batch, rngs, outputs, distances, failures, which);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = continued[j];
    seconds_[i * 2 + 1] = seconds / static_cast<double>(n);
    if (failures.failed(j)) {
      // The candidate's expensive simulation is its simulation: a failure fails the candidate.
      Fail(i, failures.reason(j));
      std::fill_n(distances_.begin() + static_cast<std::ptrdiff_t>(i * c_),
                  c_,
                  std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    std::copy_n(outputs.begin() + static_cast<std::ptrdiff_t>(j * m_),
                m_,
                outputs_.begin() + static_cast<std::ptrdiff_t>(i * m_));
    std::copy_n(distances.begin() + static_cast<std::ptrdiff_t>(j * c_),
                c_,
                distances_.begin() + static_cast<std::ptrdiff_t>(i * c_));
  }
}

Particle CandidateBatch::MakeParticle(std::int64_t i, std::int64_t index, bool keep_output) const {
  const auto u = static_cast<std::size_t>(i);
  Particle p;
  p.index = index;
  p.theta.bits.assign(bits_.begin() + static_cast<std::ptrdiff_t>(u * d_),
                      bits_.begin() + static_cast<std::ptrdiff_t>((u + 1) * d_));
  p.theta.reals.assign(reals_.begin() + static_cast<std::ptrdiff_t>(u * r_),
                       reals_.begin() + static_cast<std::ptrdiff_t>((u + 1) * r_));
  p.log_weight = log_weights_[u];
  p.distance.assign(distances_.begin() + static_cast<std::ptrdiff_t>(u * c_),
                    distances_.begin() + static_cast<std::ptrdiff_t>((u + 1) * c_));
  if (keep_output) {
    p.output.assign(outputs_.begin() + static_cast<std::ptrdiff_t>(u * m_),
                    outputs_.begin() + static_cast<std::ptrdiff_t>((u + 1) * m_));
  }
  if (low_fidelity_) {
    const auto low = low_distance(i);
    p.low_distance.assign(low.begin(), low.end());
    p.confirmed = continued(i);
  }
  return p;
}

}  // namespace combabc
