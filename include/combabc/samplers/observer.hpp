#pragma once
// Callbacks through which a run reports progress and checkpoints (the CLI's progress bar and the
// SQLite history use them). All are called on the thread that called Run(), never concurrently.
#include <cstdint>
#include <optional>
#include <span>

#include "combabc/samplers/run_history.hpp"

namespace combabc {

struct BatchProgress {
  int wave = 0;
  std::int64_t next_index = 0;  // candidates [0, next_index) of this wave are done
  std::int64_t accepted = 0;    // accepted so far in this wave
  std::int64_t discarded = 0;   // simulated in this wave past its last acceptance (final batch)
  int accepted_needed = 0;
  std::int64_t total_simulations = 0;
  double elapsed_seconds = 0.0;
  std::int64_t failures = 0;                  // failed simulations among [0, next_index)
  std::span<const SimulationFailure> failed;  // those this batch added, in candidate order
  // Multi-fidelity runs: the wave's continuation probabilities, and its expensive simulations and
  // call times over candidates [0, next_index) (what a resumed wave starts from).
  std::optional<WaveFidelity> fidelity;
};

class SmcObserver {
 public:
  virtual ~SmcObserver() = default;
  // A wave starts: its thresholds, phi and proposal are in `wave` (no particles yet), and in a
  // multi-fidelity run its continuation probabilities (wave.multi_fidelity, costs still 0).
  virtual void OnWaveStart(const WaveRecord& /*wave*/) {}
  // A batch is done; `accepted` are its newly accepted particles (weights not yet normalised).
  // After this returns, a resumed run may restart from progress.next_index.
  virtual void OnBatch(const BatchProgress& /*progress*/, std::span<const Particle> /*accepted*/) {}
  // A wave ends (complete or not), with its final statistics and normalised weights.
  virtual void OnWaveEnd(const WaveRecord& /*wave*/) {}
  // Polled between batches: true stops the run with Termination::kInterrupted.
  virtual bool ShouldStop() { return false; }
};

}  // namespace combabc
