#pragma once
// A batch of consecutive candidates of one wave, evaluated by an Executor into flat buffers (no
// allocation per candidate). Candidate i's randomness is RandomStream(seed, wave, first + i):
// the proposal draws first (the product kernels: the bits, then the reals), then whatever a
// stochastic simulator draws, then (with draw_uniform) the uniform of the noise-aware acceptance.
// With a low-fidelity stage, the simulator that draws is the cheap one, and after the acceptance
// uniform come the continuation uniform and then the expensive simulator's draws.
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "combabc/core/executor.hpp"
#include "combabc/distances/distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal.hpp"
#include "combabc/samplers/multi_fidelity.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc {

// The proposal of one wave; `from_prior` marks wave 0, whose importance weights are exactly 1.
// A resample-move round gives its candidates instead (`given_free`, `given_reals`: one row per
// candidate index, free bits and reals), and its own random streams (`stream`, in place of the
// wave's number), which the candidates' simulators draw from; their log weight is then 0.
struct WaveProposal {
  const JointProposal* proposal = nullptr;
  bool from_prior = false;
  std::span<const std::uint8_t> given_free = {};
  std::span<const double> given_reals = {};
  bool given = false;
  std::uint64_t stream = 0;
};

// What a multi-fidelity batch needs besides the expensive simulator: the cheap one, the
// continuation probabilities, and the wave's acceptance of a distance (with the candidate's
// acceptance uniform), which decides which continuation probability applies. `accept` is
// called from the executor's workers: it must be thread-safe.
struct LowFidelityStage {
  const Simulator* simulator = nullptr;
  MultiFidelityOptions options;
  std::function<bool(std::span<const double> distance, double uniform)> accept;
  // A wave whose every threshold is infinite accepts whatever either simulator says, so the
  // expensive one cannot change a weight there: it runs on a random share continue_if_rejected
  // of the candidates, whatever the cheap outcome, for what the next wave learns from it (its
  // threshold and continuation probabilities).
  bool infinite_thresholds = false;
};

class CandidateBatch : public BatchTask {
 public:
  // low_fidelity: null for a single-fidelity run.
  CandidateBatch(const ParameterSpace& space,
                 const Simulator& simulator,
                 const Distance& distance,
                 std::size_t num_components,
                 bool draw_uniform = false,
                 const LowFidelityStage* low_fidelity = nullptr);

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
  // With a low-fidelity stage: the cheap model's distance, whether the wave's rule accepted it,
  // and whether the expensive simulator ran (then distance() and the output are its own; else
  // they are the cheap model's).
  std::span<const double> low_distance(std::int64_t i) const {
    return {low_distances_.data() + i * c_, c_};
  }
  bool cheap_accepted(std::int64_t i) const {
    return (fidelity_[static_cast<std::size_t>(i)] & kCheapAccepted) != 0;
  }
  bool continued(std::int64_t i) const {
    return (fidelity_[static_cast<std::size_t>(i)] & kContinued) != 0;
  }
  // With a low-fidelity stage: the candidate's share of the wall time of the cheap and of the
  // expensive simulator call that ran it (a call's time shared equally among its candidates; 0
  // for a candidate the expensive simulator did not run). Not deterministic.
  double cheap_seconds(std::int64_t i) const { return seconds_[static_cast<std::size_t>(i) * 2]; }
  double expensive_seconds(std::int64_t i) const {
    return seconds_[static_cast<std::size_t>(i) * 2 + 1];
  }
  // The candidate's acceptance uniform on [0, 1) (0 unless draw_uniform).
  double uniform(std::int64_t i) const { return uniforms_[static_cast<std::size_t>(i)]; }
  // The candidate's log p / q (its importance weight before the multiplier).
  double log_weight(std::int64_t i) const { return log_weights_[static_cast<std::size_t>(i)]; }
  bool failed(std::int64_t i) const { return status_[static_cast<std::size_t>(i)] != 0; }
  std::string_view reason(std::int64_t i) const;
  Particle MakeParticle(std::int64_t i, std::int64_t index, bool keep_output) const;

  void EvaluateRange(std::size_t begin, std::size_t end) override;
  // Per candidate, in this order: bits (d bytes), reals (r doubles), outputs (m doubles),
  // distances (c doubles), log weight (1 double), uniform (1 double), status (1 byte: 0 =
  // simulated, 1 = failed), reason (kFailureReasonBytes, NUL-padded), low-fidelity distances (c
  // doubles), fidelity flags (1 byte: kCheapAccepted | kContinued), simulator seconds (2
  // doubles: cheap, expensive); the last three are empty rows (0 bytes) without a low-fidelity
  // stage. docs/algorithm.md.
  std::vector<Buffer> Results() override;

 private:
  static constexpr std::uint8_t kCheapAccepted = 1;
  static constexpr std::uint8_t kContinued = 2;

  // Marks candidate i failed unless it already is (the first reason wins).
  void Fail(std::size_t i, std::string_view reason);
  // Runs `simulator` on `batch` and measures the outputs: rows of m_ outputs and c_ distances; a
  // candidate whose simulation or distance failed is marked in `failures` (the first reason wins)
  // and its distances are NaN. Any other exception throws Error(kSoftware) naming `which`.
  // Returns the wall time of the simulator call, in seconds.
  double SimulateAndMeasure(const Simulator& simulator,
                            const ParameterBatch& batch,
                            std::span<RandomStream> rngs,
                            std::span<double> outputs,
                            std::span<double> distances,
                            BatchFailures& failures,
                            const std::string& which) const;
  // Candidates [begin, end), measured by the cheap simulator: draws each one's continuation and
  // runs the expensive simulator on those that continue, whose outputs and distances replace
  // the cheap ones.
  void ContinueWithExpensive(std::size_t begin, std::size_t end, const std::string& which);

  const ParameterSpace& space_;
  const Simulator& simulator_;
  const Distance& distance_;
  const LowFidelityStage* low_fidelity_;
  std::size_t d_, f_, r_, m_, c_;
  bool draw_uniform_;
  // The batch Evaluate is running.
  std::uint64_t seed_ = 0;
  int wave_ = 0;
  std::int64_t first_ = 0;
  WaveProposal proposal_;
  std::vector<std::uint8_t> free_, bits_, status_, fidelity_;
  std::vector<char> reasons_;
  std::vector<double> reals_, outputs_, distances_, low_distances_, log_weights_, uniforms_,
      seconds_;
  std::vector<RandomStream> rngs_;
};

}  // namespace combabc
