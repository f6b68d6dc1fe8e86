#include "samplers/candidate_batch.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "combabc/core/error.hpp"

namespace combabc {

CandidateBatch::CandidateBatch(const BinarySpace& space,
                               const Simulator& simulator,
                               const Distance& distance,
                               std::size_t num_components)
    : space_(space),
      simulator_(simulator),
      distance_(distance),
      d_(static_cast<std::size_t>(space.dimension())),
      f_(static_cast<std::size_t>(space.num_free())),
      m_(static_cast<std::size_t>(simulator.output_size())),
      c_(num_components) {}

void CandidateBatch::Evaluate(ThreadPool& pool,
                              std::uint64_t seed,
                              int wave,
                              std::int64_t first,
                              std::int64_t count,
                              const BernoulliProposal& proposal) {
  const auto n = static_cast<std::size_t>(count);
  free_.resize(n * f_);
  bits_.resize(n * d_);
  outputs_.resize(n * m_);
  distances_.resize(n * c_);
  log_weights_.resize(n);
  rngs_.resize(n, RandomStream(0, 0, 0));
  // Enough chunks per thread to balance uneven simulators, few enough to amortise the handoff.
  const std::size_t chunk =
      std::max<std::size_t>(1, n / (static_cast<std::size_t>(pool.size()) * 4));
  pool.ParallelFor(n, chunk, [&](std::size_t begin, std::size_t end) {
    EvaluateRange(begin, end, seed, wave, first, proposal);
  });
}

void CandidateBatch::EvaluateRange(std::size_t begin,
                                   std::size_t end,
                                   std::uint64_t seed,
                                   int wave,
                                   std::int64_t first,
                                   const BernoulliProposal& proposal) {
  auto span_of = [](auto& v, std::size_t i, std::size_t width) {
    return std::span(v.data() + i * width, width);
  };
  for (std::size_t i = begin; i < end; ++i) {
    rngs_[i] =
        RandomStream(seed, static_cast<std::uint64_t>(wave), static_cast<std::uint64_t>(first) + i);
    auto free = span_of(free_, i, f_);
    proposal.Sample(rngs_[i], free);
    space_.Expand(free, span_of(bits_, i, d_));
    log_weights_[i] = proposal.LogWeight(free);
  }
  const std::string which = "wave " + std::to_string(wave + 1) + ", candidates " +
                            std::to_string(first + static_cast<std::int64_t>(begin)) + "-" +
                            std::to_string(first + static_cast<std::int64_t>(end) - 1);
  try {
    simulator_.SimulateBatch(
        std::span<const std::uint8_t>(bits_.data() + begin * d_, (end - begin) * d_),
        std::span(rngs_.data() + begin, end - begin),
        std::span(outputs_.data() + begin * m_, (end - begin) * m_));
  } catch (const std::exception& e) {
    throw Error(ErrorKind::kSoftware, std::string("simulator failed: ") + e.what(), "", 0, which);
  }
  for (std::size_t i = begin; i < end; ++i) {
    auto out = span_of(distances_, i, c_);
    try {
      distance_.Evaluate(span_of(outputs_, i, m_), out);
    } catch (const std::exception& e) {
      throw Error(ErrorKind::kSoftware, std::string("distance failed: ") + e.what(), "", 0, which);
    }
    for (std::size_t k = 0; k < c_; ++k) {
      if (std::isnan(out[k])) {
        throw Error(ErrorKind::kSoftware,
                    "distance component " + std::to_string(k) +
                        " is NaN (the simulated output holds NaN or the distance is undefined)",
                    "",
                    0,
                    "wave " + std::to_string(wave + 1) + ", candidate " +
                        std::to_string(first + static_cast<std::int64_t>(i)));
      }
    }
  }
}

Particle CandidateBatch::MakeParticle(std::int64_t i, std::int64_t index, bool keep_output) const {
  const auto u = static_cast<std::size_t>(i);
  Particle p;
  p.index = index;
  p.bits.assign(bits_.begin() + static_cast<std::ptrdiff_t>(u * d_),
                bits_.begin() + static_cast<std::ptrdiff_t>((u + 1) * d_));
  p.log_weight = log_weights_[u];
  p.distance.assign(distances_.begin() + static_cast<std::ptrdiff_t>(u * c_),
                    distances_.begin() + static_cast<std::ptrdiff_t>((u + 1) * c_));
  if (keep_output) {
    p.output.assign(outputs_.begin() + static_cast<std::ptrdiff_t>(u * m_),
                    outputs_.begin() + static_cast<std::ptrdiff_t>((u + 1) * m_));
  }
  return p;
}

}  // namespace combabc
