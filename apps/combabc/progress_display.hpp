#pragma once
// The run's progress on stderr: on a terminal a single updating line per wave (wave, accepted /
// needed, acceptance rate, ETA); otherwise one line per finished wave, so logs stay readable.
// Waves are numbered from 1 here, like the paper and the report's figures (the engine, the
// history file and the export count from 0).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "combabc/samplers/observer.hpp"

namespace combabc::cli {

class ProgressDisplay : public SmcObserver {
 public:
  // `temperatures`: per threshold slot, whether it holds a noise-aware component's temperature
  // (docs/algorithm.md, "Noise-aware acceptance"); empty or of another size: every slot an eps.
  explicit ProgressDisplay(bool terminal, std::vector<bool> temperatures = {})
      : terminal_(terminal), temperatures_(std::move(temperatures)) {}

  void OnWaveStart(const WaveRecord& wave) override {
    wave_start_ = std::chrono::steady_clock::now();
    wave_ = wave.wave;
    // Only an enumeration knows its candidates in advance: then progress is candidates done.
    total_ = wave.candidates;
  }

  void OnBatch(const BatchProgress& p, std::span<const Particle>) override {
    if (!terminal_) return;
    const double elapsed = Elapsed();
    const auto accepted = static_cast<double>(p.accepted);
    const double rate = p.next_index > 0 ? accepted / static_cast<double>(p.next_index) : 0.0;
    double eta = p.accepted > 0 ? elapsed * (p.accepted_needed - accepted) / accepted : 0.0;
    constexpr int kWidth = 24;
    int filled = static_cast<int>(kWidth * p.accepted / std::max(1, p.accepted_needed));
    if (total_ > 0) {
      const auto done = static_cast<double>(p.next_index);
      eta = done > 0 ? elapsed * (static_cast<double>(total_) - done) / done : 0.0;
      filled = static_cast<int>(kWidth * p.next_index / total_);
    }
    char bar[kWidth + 1];
    for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
    bar[kWidth] = '\0';
    if (total_ > 0) {
      std::fprintf(stderr,
                   "\renumerate [%s] %lld/%lld configurations  %lld accepted  %.1f s  ETA %.1f s  ",
                   bar,
                   static_cast<long long>(p.next_index),
                   static_cast<long long>(total_),
                   static_cast<long long>(p.accepted),
                   elapsed,
                   eta);
    } else {
      std::fprintf(stderr,
                   "\rwave %d [%s] %lld/%d accepted  rate %.4f  %lld sims  %.1f s  ETA %.1f s  ",
                   p.wave + 1,
                   bar,
                   static_cast<long long>(p.accepted),
                   p.accepted_needed,
                   rate,
                   static_cast<long long>(p.total_simulations),
                   elapsed,
                   eta);
      if (p.failures > 0) std::fprintf(stderr, "%lld failed  ", static_cast<long long>(p.failures));
      if (p.fidelity) {
        std::fprintf(
            stderr, "%lld expensive  ", static_cast<long long>(p.fidelity->expensive_simulations));
      }
    }
    std::fflush(stderr);
    dirty_ = true;
  }

  void OnWaveEnd(const WaveRecord& w) override {
    Clear();
    std::fprintf(
        stderr,
        "wave %d: %s  %lld/%lld accepted (rate %.4f)%s  ESS %.0f  %.2f s%s\n",
        w.wave + 1,
        Thresholds(w.thresholds).c_str(),
        static_cast<long long>(w.accepted),
        static_cast<long long>(w.candidates),
        w.acceptance_rate,
        w.failures.empty() ? "" : ("  " + std::to_string(w.failures.size()) + " failed").c_str(),
        w.ess,
        w.wall_seconds,
        w.complete ? "" : "  (incomplete)");
    if (w.multi_fidelity) {
      // Multi-fidelity: every candidate ran the cheap simulator, these the expensive one too.
      std::fprintf(
          stderr,
          "        %lld expensive of %lld  (continue if accepted %.3g, if rejected %.3g)\n",
          static_cast<long long>(w.multi_fidelity->expensive_simulations),
          static_cast<long long>(w.candidates),
          w.multi_fidelity->continue_if_accepted,
          w.multi_fidelity->continue_if_rejected);
    }
    if (w.moves) {
      // Resample-move: the proposals are the wave's candidates (one simulation each).
      const WaveMoves& m = *w.moves;
      std::fprintf(stderr,
                   "        moves: %d rounds, %lld proposals, %s accepted; %s independent; "
                   "survivors' ESS %.0f%s\n",
                   m.rounds,
                   static_cast<long long>(m.proposed),
                   Percent(m.accepted, m.proposed).c_str(),
                   Percent(m.independent_proposed, m.proposed).c_str(),
                   m.survivor_ess,
                   m.step < 1.0 ? (", step " + Format(m.step)).c_str() : "");
    }
    // The mode-loss diagnostic (docs/algorithm.md, "Mode loss"): known when the wave started,
    // said under its line.
    const std::string mode_loss = ModeLossWarning(w);
    if (!mode_loss.empty()) std::fprintf(stderr, "warning: %s\n", mode_loss.c_str());
  }

  void Clear() {
    if (dirty_) std::fputs("\r\033[K", stderr);
    dirty_ = false;
  }

 private:
  // "31%" of a count, "-" without any.
  static std::string Percent(std::int64_t part, std::int64_t whole) {
    if (whole <= 0) return "-";
    char b[32];
    std::snprintf(
        b, sizeof b, "%.0f%%", 100.0 * static_cast<double>(part) / static_cast<double>(whole));
    return b;
  }
  // The first wave has no threshold (every prior draw is accepted: an infinite eps or
  // temperature, which the engine may record as NaN): shown as infinity.
  static std::string Format(double x) {
    if (!std::isfinite(x)) return Utf8() ? "∞" : "inf";
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", x);
    return b;
  }
  // "eps 0.12,0.3", or with noise-aware components "eps 0.12, temperature 3.4".
  std::string Thresholds(const std::vector<double>& values) const {
    const bool labelled = temperatures_.size() == values.size();
    std::string out;
    for (std::size_t k = 0; k < values.size(); ++k) {
      const bool temperature = labelled && temperatures_[k];
      if (k == 0 || temperature != (labelled && temperatures_[k - 1])) {
        out += std::string(k == 0 ? "" : ", ") + (temperature ? "temperature " : "eps ");
      } else {
        out += ",";
      }
      out += Format(values[k]);
    }
    return out.empty() ? "eps -" : out;
  }
  // Whether the terminal's locale writes UTF-8 (LC_ALL, else LC_CTYPE, else LANG).
  static bool Utf8() {
    for (const char* name : {"LC_ALL", "LC_CTYPE", "LANG"}) {
      const char* value = std::getenv(name);
      if (value == nullptr || *value == '\0') continue;
      const std::string text = value;
      return text.find("UTF-8") != std::string::npos || text.find("utf8") != std::string::npos ||
             text.find("utf-8") != std::string::npos || text.find("UTF8") != std::string::npos;
    }
    return false;
  }
  double Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wave_start_).count();
  }

  bool terminal_;
  std::vector<bool> temperatures_;
  bool dirty_ = false;
  int wave_ = 0;
  std::int64_t total_ = 0;
  std::chrono::steady_clock::time_point wave_start_;
};

}  // namespace combabc::cli
