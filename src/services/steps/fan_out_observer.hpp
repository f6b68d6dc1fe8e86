#pragma once
// Forwards every engine callback to several observers (history store, progress display).
#include <vector>

#include "combabc/samplers/observer.hpp"

namespace combabc::services {

class FanOutObserver : public SmcObserver {
 public:
  explicit FanOutObserver(const std::vector<SmcObserver*>& observers) {
    for (auto* o : observers) {
      if (o) observers_.push_back(o);
    }
  }
  void OnWaveStart(const WaveRecord& wave) override {
    for (auto* o : observers_) o->OnWaveStart(wave);
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    for (auto* o : observers_) o->OnBatch(progress, accepted);
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    for (auto* o : observers_) o->OnWaveEnd(wave);
  }
  bool ShouldStop() override {
    bool stop = false;
    for (auto* o : observers_) stop = o->ShouldStop() || stop;
    return stop;
  }

 private:
  std::vector<SmcObserver*> observers_;
};

}  // namespace combabc::services
