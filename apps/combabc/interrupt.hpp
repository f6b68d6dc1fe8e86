#pragma once
// SIGINT / SIGTERM handling, separate from the progress display so that -q runs stop the same way.
//
// A signal stops the run gracefully (at the next batch boundary, resumable, exit 130) only while a
// wave is being sampled: that is the only stage with resumable work in flight. Before (reading the
// config, possibly from a FIFO; building the model) and after (the report) a signal keeps its
// default action and ends the process at once, and so does a second signal during a wave, so the
// program is killable at every stage. (While the report's Python script runs, services'
// RunProcess holds the signal until it has interrupted and reaped the script, then re-raises it.)
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <string>

#include "combabc/core/output_files.hpp"
#include "combabc/samplers/observer.hpp"

namespace combabc::cli {

namespace interrupt_internal {
inline std::atomic<bool> armed{false};
inline std::atomic<bool> requested{false};
// The line SIGTERM prints first (SetTermNote); empty: none. Written with write(2), the only
// output a signal handler may make.
inline char term_note[2048];
inline std::atomic<std::size_t> term_note_size{0};
inline std::atomic<bool> term_noted{false};

extern "C" inline void OnSignal(int signal_number) {
  const std::size_t note = term_note_size.load();
  if (signal_number == SIGTERM && note > 0 && !term_noted.exchange(true)) {
    [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, term_note, note);
  }
  if (!armed.load() || requested.exchange(true)) {
    // Nothing resumable in flight, or the user insists: die by the signal (default action),
    // leaving no temporary behind (an export's staged files; no destructor runs).
    RemovePendingOutputs();
    ::signal(signal_number, SIG_DFL);
    ::raise(signal_number);
  }
}
}  // namespace interrupt_internal

static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs lock-free flags");
static_assert(std::atomic<std::size_t>::is_always_lock_free,
              "the signal handler needs a lock-free size");

// Under mpirun, the line rank 0 prints on SIGTERM before the signal takes its usual course.
// mpirun ends a job whose rank died (or that was itself signalled) by SIGCONT, SIGTERM and, one
// second later (odls_base_sigkill_timeout), SIGKILL to every surviving rank; rank 0 is then
// usually blocked in a collective with the dead rank and would die without a word (docs/mpi.md).
inline void SetTermNote(const std::string& line) {
  interrupt_internal::term_note_size = 0;  // not read while it changes
  const std::size_t size = std::min(line.size(), sizeof interrupt_internal::term_note);
  std::copy_n(line.data(), size, interrupt_internal::term_note);
  interrupt_internal::term_note_size = size;
}

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
