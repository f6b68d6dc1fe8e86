#pragma once
// A batch of consecutive candidates of one wave, evaluated in parallel into flat buffers (no
// allocation per candidate). Candidate i's randomness is RandomStream(seed, wave, first + i):
// proposal draws first, then whatever a stochastic simulator draws.
#include <cstdint>
#include <span>
#include <vector>

#include "combabc/core/thread_pool.hpp"
#include "combabc/distances/distance.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/proposals/bernoulli_proposal.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc {

class CandidateBatch {
 public:
  CandidateBatch(const BinarySpace& space,
                 const Simulator& simulator,
                 const Distance& distance,
                 std::size_t num_components);

  // Proposes, simulates and measures candidates [first, first + count) of `wave`. Throws
  // Error(kSoftware) naming the wave and candidates if the simulator or distance fails.
  void Evaluate(ThreadPool& pool,
                std::uint64_t seed,
                int wave,
                std::int64_t first,
                std::int64_t count,
                const BernoulliProposal& proposal);

  std::span<const double> distance(std::int64_t i) const {
    return {distances_.data() + i * c_, c_};
  }
  Particle MakeParticle(std::int64_t i, std::int64_t index, bool keep_output) const;

 private:
  void EvaluateRange(std::size_t begin,
                     std::size_t end,
                     std::uint64_t seed,
                     int wave,
                     std::int64_t first,
                     const BernoulliProposal& proposal);

  const BinarySpace& space_;
  const Simulator& simulator_;
  const Distance& distance_;
  std::size_t d_, f_, m_, c_;
  std::vector<std::uint8_t> free_, bits_;
  std::vector<double> outputs_, distances_, log_weights_;
  std::vector<RandomStream> rngs_;
};

}  // namespace combabc
