// A signal held while a child runs, and the wait that forwards it to the child
// (core/subprocess.hpp): the Python scripts are interrupted and reaped before combabc ends by the
// signal, so that none publishes after combabc is gone.
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <optional>

#include "combabc/core/subprocess.hpp"

namespace combabc {
namespace {

std::atomic<int> held_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void RecordSignal(int signal_number) { held_signal.store(signal_number); }

// How soon a held signal is forwarded: the longest a wait sleeps before looking.
constexpr std::chrono::milliseconds kSignalLatency{100};

}  // namespace

SignalHold::SignalHold() {
  held_signal.store(0);
  struct sigaction action = {};
  action.sa_handler = RecordSignal;
  sigemptyset(&action.sa_mask);
  for (std::size_t k = 0; k < 2; ++k) {
    ::sigaction(kSignals[k], nullptr, &old_[k]);
    installed_[k] = old_[k].sa_handler != SIG_IGN;
    if (installed_[k]) ::sigaction(kSignals[k], &action, nullptr);
  }
}

int SignalHold::signal() const { return held_signal.load(); }

void SignalHold::Release() {
  for (std::size_t k = 0; k < 2; ++k) {
    if (installed_[k]) ::sigaction(kSignals[k], &old_[k], nullptr);
    installed_[k] = false;
  }
}

ExitStatus Subprocess::WaitForwarding(const SignalHold& hold, std::chrono::milliseconds grace) {
  using Clock = std::chrono::steady_clock;
  std::optional<Clock::time_point> kill_at;  // set once the child was interrupted
  for (;;) {
    if (!kill_at && hold.signal() != 0) {
      ::kill(-pid_, SIGINT);
      kill_at = Clock::now() + grace;
    }
    if (kill_at && Clock::now() >= *kill_at) return Kill();
    Deadline next = Clock::now() + kSignalLatency;
    if (kill_at) next = std::min(next, *kill_at);
    if (const std::optional<ExitStatus> status = Wait(next)) return *status;
    timed_out_ = false;  // a look at the signal, not a deadline the caller set
  }
}

}  // namespace combabc
