#pragma once
// A batch of consecutive candidates of one wave, evaluated by an Executor into flat buffers (no
// allocation per candidate). Candidate i's randomness is RandomStream(seed, wave, first + i):
// the binary proposal draws first, then the continuous one, then whatever a stochastic
// simulator draws, then (with draw_uniform) the uniform of the noise-aware acceptance.
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "combabc/core/executor.hpp"
#include "combabc/distances/distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc {

// The proposals of one wave; `from_prior` marks wave 0, whose importance weights are exactly 1.
struct WaveProposal {
  const BinaryProposal* bits = nullptr;
  const ContinuousProposal* reals = nullptr;  // null when the space has no reals
  bool from_prior = false;
};

class CandidateBatch : public BatchTask {
 public:
  CandidateBatch(const ParameterSpace& space,
                 const Simulator& simulator,
                 const Distance& distance,
                 std::size_t num_components,
                 bool draw_uniform = false);

  // Proposes, simulates and measures candidates [first, first + count) of `wave` (the simulator
  // and the distance called once per range of candidates). A candidate whose simulation failed
  // (SimulationFailed, an output or distance holding NaN, a candidate the distance failed) is
  // marked failed with its reason; any other simulator or distance exception throws
  // Error(kSoftware) naming the wave and candidates.
  void Evaluate(Executor& executor,
                std::uint64_t seed,
                int wave,
                std::int64_t first,
                std::int64_t count,
                const WaveProposal& proposal);

  std::span<const double> distance(std::int64_t i) const {
    return {distances_.data() + i * c_, c_};
  }
  // The candidate's acceptance uniform on [0, 1) (0 unless draw_uniform).
  double uniform(std::int64_t i) const { return uniforms_[static_cast<std::size_t>(i)]; }
  bool failed(std::int64_t i) const { return status_[static_cast<std::size_t>(i)] != 0; }
  std::string_view reason(std::int64_t i) const;
  Particle MakeParticle(std::int64_t i, std::int64_t index, bool keep_output) const;

  void EvaluateRange(std::size_t begin, std::size_t end) override;
  // Per candidate, in this order: bits (d bytes), reals (r doubles), outputs (m doubles),
  // distances (c doubles), log weight (1 double), uniform (1 double), status (1 byte: 0 =
  // simulated, 1 = failed), reason (kFailureReasonBytes, NUL-padded). docs/algorithm.md.
  std::vector<Buffer> Results() override;

 private:
  // Marks candidate i failed unless it already is (the first reason wins).
  void Fail(std::size_t i, std::string_view reason);

  const ParameterSpace& space_;
  const Simulator& simulator_;
  const Distance& distance_;
  std::size_t d_, f_, r_, m_, c_;
  bool draw_uniform_;
  // The batch Evaluate is running.
  std::uint64_t seed_ = 0;
  int wave_ = 0;
  std::int64_t first_ = 0;
  WaveProposal proposal_;
  std::vector<std::uint8_t> free_, bits_, status_;
  std::vector<char> reasons_;
  std::vector<double> reals_, outputs_, distances_, log_weights_, uniforms_;
  std::vector<RandomStream> rngs_;
};

}  // namespace combabc
