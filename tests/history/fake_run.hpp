#pragma once
// A synthetic but realistic-looking run (clamped-plate style: 2 x 18 clamps, normalised
// displacement curves peaking at the impact point) for history, export and report tests. Not a
// simulation: curves come from a cheap closed form so that tests need no engine or FE model.
#include <cstdint>
#include <string>
#include <vector>

#include "combabc/history/history_store.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc::testing {

struct FakeRunOptions {
  int waves = 3;
  int per_wave = 20;
  int dimension = 36;   // even with "clamp" names: two edges of dimension/2 clamps
  int points = 91;      // output positions 0 .. 0.9 m
  bool outputs = true;  // store curves
  // Continuous parameters ("stiffness_1", ...: uniform priors on [1e4, 1e5]) drawn per particle;
  // they do not change the curves, only what is stored and exported.
  int reals = 0;
  // A multi-fidelity run: every third particle confirmed (multiplier 1, 1/eta_2 or 1 - 1/eta_1
  // in turn), the others not (1); cheap distances 10 % above the expensive ones; each wave's
  // continuation probabilities (kFakeFidelity) and made-up costs.
  bool multi_fidelity = false;
  // Each wave after the first records two pattern classes of the previous wave (the mode-loss
  // diagnostic): its first particle's bits (mass 0.6, proposal 0.5) and its second's (mass 0.05,
  // proposal 1e-6, flagged).
  bool pattern_classes = false;
  // Each wave after the first is recorded as a resample-move wave: made-up move statistics
  // (kFakeMoveRounds rounds of one proposal per particle, a third accepted, half of them
  // independent) and each particle's ancestor, the previous wave's particles in turn. The
  // particles themselves are drawn as in any other fake wave.
  bool moves = false;
  std::uint64_t seed = 7;
};

// The continuation probabilities of a multi-fidelity fake run's waves: eta_1 = 0.8, eta_2 = 0.25.
inline constexpr double kFakeContinueIfAccepted = 0.8;
inline constexpr double kFakeContinueIfRejected = 0.25;

inline constexpr int kFakeMoveRounds = 3;

RunMetadata MakeFakeMetadata(const FakeRunOptions& options);
// Complete waves with statistics from ComputeWaveStatistics (paper estimator).
RunHistory MakeFakeHistory(const FakeRunOptions& options);

// Feeds `wave` to the observer as the engine would: OnWaveStart, then OnBatch per `batch`
// candidates (particles grouped by candidate index), then OnWaveEnd unless stop_after_batches >= 0,
// in which case it stops (as if killed) after that many batches. A multi-fidelity wave's batches
// carry its costs in proportion to the candidates done (BatchProgress::fidelity).
void RecordWave(SmcObserver& observer,
                const WaveRecord& wave,
                std::int64_t batch,
                int stop_after_batches = -1);

}  // namespace combabc::testing
