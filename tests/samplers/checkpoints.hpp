#pragma once
// An observer that records the run's state at every checkpoint, as the SQLite history does: a
// resume point after each batch (the wave's particles so far, its multi-fidelity state) and one
// between waves (killed after a wave ended, before the next one's first batch).
#include <span>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/observer.hpp"

namespace combabc::testing {

class Checkpoints : public SmcObserver {
 public:
  void OnWaveStart(const WaveRecord& w) override { current_.clear(), wave_ = w.wave; }
  void OnBatch(const BatchProgress& p, std::span<const Particle> accepted) override {
    current_.insert(current_.end(), accepted.begin(), accepted.end());
    ResumePoint r;
    r.completed = completed_;
    r.has_partial = true;
    r.partial_wave = wave_;
    r.partial_next_index = p.next_index;
    r.partial_accepted = current_;
    r.partial_discarded = p.discarded;
    r.partial_fidelity = p.fidelity;
    points.push_back(std::move(r));
  }
  void OnWaveEnd(const WaveRecord& w) override {
    if (!w.complete) return;
    completed_.push_back(w);
    ResumePoint between_waves;
    between_waves.completed = completed_;
    points.push_back(std::move(between_waves));
  }
  std::vector<ResumePoint> points;

 private:
  int wave_ = 0;
  std::vector<Particle> current_;
  std::vector<WaveRecord> completed_;
};

}  // namespace combabc::testing
