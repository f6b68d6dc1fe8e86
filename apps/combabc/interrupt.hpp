#pragma once
// SIGINT / SIGTERM handling, separate from the progress display so that -q runs stop the same way.
//
// A signal stops the run gracefully (at the next batch boundary, resumable, exit 130) only while a
// wave is being sampled: that is the only stage with resumable work in flight. Before (reading the
// config, possibly from a FIFO; building the model) and after (the report) a signal keeps its
// default action and ends the process at once, and so does a second signal during a wave, so the
// program is killable at every stage.
#include <signal.h>

#include <atomic>

#include "combabc/samplers/observer.hpp"

namespace combabc::cli {

namespace interrupt_internal {
inline std::atomic<bool> armed{false};
inline std::atomic<bool> requested{false};

extern "C" inline void OnSignal(int signal_number) {
  if (!armed.load() || requested.exchange(true)) {
    // Nothing resumable in flight, or the user insists: die by the signal (default action).
    ::signal(signal_number, SIG_DFL);
    ::raise(signal_number);
  }
}
}  // namespace interrupt_internal

static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs lock-free flags");

// Wraps the display (or nothing, with -q): arms the graceful handler while a wave runs and asks
// the engine to stop once a signal came.
class InterruptObserver : public SmcObserver {
 public:
  explicit InterruptObserver(SmcObserver* display) : display_(display) {
    struct sigaction action = {};
    action.sa_handler = interrupt_internal::OnSignal;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
  }
  ~InterruptObserver() override { interrupt_internal::armed = false; }
  InterruptObserver(const InterruptObserver&) = delete;
  InterruptObserver& operator=(const InterruptObserver&) = delete;

  void OnWaveStart(const WaveRecord& wave) override {
    if (display_) display_->OnWaveStart(wave);
    interrupt_internal::armed = true;
  }
  void OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) override {
    if (display_) display_->OnBatch(progress, accepted);
  }
  void OnWaveEnd(const WaveRecord& wave) override {
    // The wave is checkpointed (the history store is notified first): a signal from here on may
    // end the process directly and the run stays resumable.
    interrupt_internal::armed = false;
    if (display_) display_->OnWaveEnd(wave);
  }
  bool ShouldStop() override { return Requested(); }

  static bool Requested() { return interrupt_internal::requested.load(); }

 private:
  SmcObserver* display_;
};

}  // namespace combabc::cli
