#include "combabc/samplers/run_history.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <unordered_map>

namespace combabc {

std::string RunSummary::BriefReport() const {
  char buf[128];
  std::snprintf(buf,
                sizeof buf,
                "%s: %d waves, %lld simulations",
                ToString(termination),
                waves_completed,
                static_cast<long long>(simulations));
  std::string text = buf;
  if (failures > 0) text += " (" + std::to_string(failures) + " failed)";
  std::snprintf(buf, sizeof buf, ", %.3f s (", wall_seconds);
  return text + buf + message + ")";
}

std::string RunHistory::FullReport(Estimator estimator) const {
  std::ostringstream out;
  out << "combinatorial ABC-SMC, estimator = " << ToString(estimator) << "\n";
  out << "wave  thresholds            candidates  accepted  rate      ESS      distinct  seconds\n";
  for (const auto& w : waves) {
    std::string eps;
    for (double e : w.thresholds) {
      char b[32];
      std::snprintf(b, sizeof b, "%s%.4g", eps.empty() ? "" : ",", e);
      eps += b;
    }
    char line[256];
    std::snprintf(line,
                  sizeof line,
                  "%4d  %-20s  %10lld  %8lld  %.5f  %7.1f  %8lld  %7.3f%s\n",
                  w.wave + 1,  // users number waves from 1, as the paper does
                  eps.c_str(),
                  static_cast<long long>(w.candidates),
                  static_cast<long long>(w.accepted),
                  w.acceptance_rate,
                  w.ess,
                  static_cast<long long>(w.distinct),
                  w.wall_seconds,
                  w.complete ? "" : "  (incomplete)");
    out << line;
  }
  out << summary.BriefReport() << "\n";
  return out.str();
}

BitMoments::BitMoments(std::size_t bits) : d_(bits), ones_(bits, 0.0), pairs_(bits * bits, 0.0) {}

void BitMoments::Add(std::span<const std::uint8_t> bits, double weight) {
  total_ += weight;
  set_.clear();
  for (std::size_t k = 0; k < d_; ++k) {
    if (bits[k]) set_.push_back(k);
  }
  // Only the set bits: a member costs (its number of ones)^2 / 2, not d^2 / 2.
  for (std::size_t a = 0; a < set_.size(); ++a) {
    ones_[set_[a]] += weight;
    for (std::size_t b = a + 1; b < set_.size(); ++b) pairs_[set_[a] * d_ + set_[b]] += weight;
  }
}

void BitMoments::Scale(double factor) {
  total_ *= factor;
  for (double& x : ones_) x *= factor;
  for (double& x : pairs_) x *= factor;
}

std::vector<double> BitMoments::Marginals() const {
  std::vector<double> marginals(d_);
  for (std::size_t k = 0; k < d_; ++k) marginals[k] = ones_[k] / total_;
  return marginals;
}

std::vector<double> BitMoments::Correlations() const {
  const std::vector<double> m = Marginals();
  std::vector<double> r(d_ * d_, 0.0);
  // A bit is constant exactly when its sum is 0 or, summed over the same weights in the same
  // order, equal to the total. Signed (multi-fidelity) weights can put a marginal at or beyond
  // 0 or 1 without that: such a bit has no variance to correlate either.
  std::vector<bool> constant(d_);
  for (std::size_t k = 0; k < d_; ++k) {
    constant[k] = ones_[k] == 0.0 || ones_[k] == total_ || !(m[k] > 0.0 && m[k] < 1.0);
  }
  for (std::size_t i = 0; i < d_; ++i) {
    if (constant[i]) continue;
    r[i * d_ + i] = 1.0;
    for (std::size_t j = i + 1; j < d_; ++j) {
      if (constant[j]) continue;
      const double cov = pairs_[i * d_ + j] / total_ - m[i] * m[j];
      const double rho =
          std::clamp(cov / std::sqrt(m[i] * (1 - m[i]) * m[j] * (1 - m[j])), -1.0, 1.0);
      r[i * d_ + j] = rho;
      r[j * d_ + i] = rho;
    }
  }
  return r;
}

std::vector<double> PairCorrelations(const std::vector<Particle>& particles) {
  if (particles.empty() || particles.front().theta.bits.size() > kMaxPairCorrelationBits) return {};
  BitMoments moments(particles.front().theta.bits.size());
  for (const Particle& p : particles) moments.Add(p.theta.bits, p.weight);
  return moments.Correlations();
}

void ComputeWaveStatistics(WaveRecord& wave, Estimator estimator) {
  const auto n = wave.particles.size();
  wave.accepted = static_cast<std::int64_t>(n);
  wave.acceptance_rate =
      wave.candidates > 0 ? static_cast<double>(n) / static_cast<double>(wave.candidates) : 0.0;
  const std::size_t d = n ? wave.particles[0].theta.bits.size() : wave.marginals_paper.size();
  const std::size_t r = n ? wave.particles[0].theta.reals.size() : wave.reals_mean.size();
  wave.marginals_paper.assign(d, 0.0);
  wave.marginals_importance.assign(d, 0.0);
  wave.reals_mean.assign(r, 0.0);
  wave.reals_sd.assign(r, 0.0);
  if (n == 0) {
    wave.ess = 0.0;
    wave.distinct = 0;
    wave.pair_correlations.clear();
    return;
  }
  // Self-normalised weights: w_i ∝ m_i p(theta_i)/q(theta_i) (importance, in log space for
  // range) or w_i ∝ m_i (paper), m_i the multi-fidelity multiplier (1 without a low-fidelity
  // simulator). Multi-fidelity weights may be negative: they are normalised by their signed sum,
  // as Prescott & Baker (2021, arXiv:2001.06256) normalise their estimators, so that every
  // estimate below stays the unbiased-ratio estimate of the expensive model's ABC posterior. A
  // wave whose signed sum is not positive (possible only with many negative weights) has no such
  // estimate; it is normalised by the sum of |w_i| instead, so that its statistics stay finite.
  double max_lw = -INFINITY;
  for (const auto& p : wave.particles) max_lw = std::max(max_lw, p.log_weight);
  std::vector<double> w(n);
  std::vector<double> paper(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = wave.particles[i];
    w[i] = p.multiplier * std::exp(p.log_weight - max_lw);
    paper[i] = p.multiplier;
  }
  // Returns whether the signed sum was positive.
  auto normalise = [](std::vector<double>& v) {
    double sum = 0.0;
    double sum_abs = 0.0;
    for (double x : v) {
      sum += x;
      sum_abs += std::abs(x);
    }
    const double norm = sum > 0.0 ? sum : sum_abs;
    for (auto& x : v) x /= norm;
    return sum > 0.0;
  };
  const bool positive_sum = normalise(w);
  normalise(paper);
  double sum_sq = 0.0;
  for (double x : w) sum_sq += x * x;
  // (sum w)^2 / sum w^2 with the normalised weights; with negative weights it is Prescott &
  // Baker's effective sample size of a signed estimator (Def. 3), 0 like theirs when the signed
  // sum is not positive.
  wave.ess = positive_sum ? 1.0 / sum_sq : 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    auto& p = wave.particles[i];
    p.weight = estimator == Estimator::kPaper ? paper[i] : w[i];
    for (std::size_t k = 0; k < d; ++k) {
      if (p.theta.bits[k]) {
        wave.marginals_paper[k] += paper[i];
        wave.marginals_importance[k] += w[i];
      }
    }
    for (std::size_t k = 0; k < r; ++k) wave.reals_mean[k] += p.weight * p.theta.reals[k];
  }
  // Signed weights can put an estimate just outside its range (a probability below 0 or above
  // 1, a negative variance): clamped, which only moves an estimate that is already at the edge.
  // Only then, so that a wave of positive weights keeps its sums bit for bit.
  const bool signed_weights = std::any_of(wave.particles.begin(),
                                          wave.particles.end(),
                                          [](const Particle& p) { return p.multiplier < 0; });
  if (signed_weights) {
    for (auto* marginals : {&wave.marginals_paper, &wave.marginals_importance}) {
      for (auto& m : *marginals) m = std::clamp(m, 0.0, 1.0);
    }
  }
  for (const auto& p : wave.particles) {
    for (std::size_t k = 0; k < r; ++k) {
      const double dev = p.theta.reals[k] - wave.reals_mean[k];
      wave.reals_sd[k] += p.weight * dev * dev;
    }
  }
  for (auto& v : wave.reals_sd) v = std::max(v, 0.0);
  for (auto& v : wave.reals_sd) v = std::sqrt(v);
  wave.pair_correlations = PairCorrelations(wave.particles);
  // Distinct bit configurations (the reals of a continuous kernel are almost surely all distinct).
  std::vector<const std::vector<std::uint8_t>*> configs;
  configs.reserve(n);
  for (const auto& p : wave.particles) configs.push_back(&p.theta.bits);
  std::sort(configs.begin(), configs.end(), [](auto* a, auto* b) { return *a < *b; });
  wave.distinct = 1;
  for (std::size_t i = 1; i < n; ++i) wave.distinct += *configs[i] != *configs[i - 1];
}

namespace {

template <typename T>
bool Differ(const T& a, const T& b, const std::string& what, std::string* where) {
  if (a == b) return false;
  if (where) *where = what;
  return true;
}

}  // namespace

std::string PatternText(const std::vector<std::uint8_t>& bits) {
  constexpr std::size_t kShown = 64;
  std::string text;
  if (bits.size() > kShown && std::count(bits.begin(), bits.end(), kAnyBit) > 0) {
    for (std::size_t k = 0; k < bits.size(); ++k) {
      if (bits[k] == kAnyBit) continue;
      text += (text.empty() ? "bit " : ", bit ") + std::to_string(k + 1) + " = " +
              (bits[k] ? "1" : "0");
    }
    return text;
  }
  for (std::size_t k = 0; k < std::min(bits.size(), kShown); ++k) {
    text += bits[k] == kAnyBit ? '-' : bits[k] ? '1' : '0';
  }
  if (bits.size() > kShown) {
    const auto set = std::count_if(bits.begin(), bits.end(), [](std::uint8_t b) { return b == 1; });
    text += "... (" + std::to_string(set) + " of " + std::to_string(bits.size()) + " bits set)";
  }
  return text;
}

std::string ModeLossWarning(const WaveRecord& wave) {
  const PatternClass* first = nullptr;
  int more = 0;
  for (const PatternClass& c : wave.pattern_classes) {
    if (!c.flagged) continue;
    if (first == nullptr) {
      first = &c;
    } else {
      ++more;
    }
  }
  if (first == nullptr) return "";
  char numbers[96];
  std::snprintf(
      numbers, sizeof numbers, " (mass %.3g) with probability %.2g", first->mass, first->proposal);
  std::string text = "wave " + std::to_string(wave.wave + 1) + " proposed pattern " +
                     PatternText(first->bits) + numbers;
  if (more > 0) {
    text +=
        " (and " + std::to_string(more) + " more pattern" + (more > 1 ? "s" : "") + " likewise)";
  }
  return text + "; the posterior may have lost a mode";
}

void AssignEveIndices(std::vector<WaveRecord>& waves) {
  for (std::size_t t = 1; t < waves.size(); ++t) {
    if (!waves[t].moves) continue;
    const WaveRecord& previous = waves[t - 1];
    std::unordered_map<std::int64_t, std::int64_t> eve_of;
    for (const Particle& p : previous.particles) {
      eve_of[p.index] = previous.moves ? p.eve : p.index;
    }
    for (Particle& p : waves[t].particles) {
      const auto it = eve_of.find(p.ancestor);
      p.eve = it == eve_of.end() ? -1 : it->second;
    }
  }
}

bool SameHistory(const RunHistory& a, const RunHistory& b, std::string* where) {
  if (Differ(a.waves.size(), b.waves.size(), "number of waves", where)) return false;
  for (std::size_t t = 0; t < a.waves.size(); ++t) {
    const auto& x = a.waves[t];
    const auto& y = b.waves[t];
    const std::string w = "wave " + std::to_string(t) + ": ";
    if (Differ(x.wave, y.wave, w + "wave", where) ||
        Differ(x.thresholds, y.thresholds, w + "thresholds", where) ||
        Differ(x.phi, y.phi, w + "phi", where) ||
        Differ(x.proposal, y.proposal, w + "proposal", where) ||
        Differ(x.candidates, y.candidates, w + "candidates", where) ||
        Differ(x.accepted, y.accepted, w + "accepted", where) ||
        Differ(x.complete, y.complete, w + "complete", where) ||
        Differ(x.marginals_paper, y.marginals_paper, w + "marginals_paper", where) ||
        Differ(x.marginals_importance, y.marginals_importance, w + "marginals_importance", where) ||
        Differ(x.ess, y.ess, w + "ess", where) ||
        Differ(x.reals_mean, y.reals_mean, w + "reals_mean", where) ||
        Differ(x.reals_sd, y.reals_sd, w + "reals_sd", where) ||
        Differ(x.distinct, y.distinct, w + "distinct", where) ||
        Differ(x.pair_correlations, y.pair_correlations, w + "pair_correlations", where) ||
        Differ(x.failures, y.failures, w + "failures", where) ||
        Differ(x.pattern_classes, y.pattern_classes, w + "pattern_classes", where) ||
        Differ(x.multi_fidelity.has_value(), y.multi_fidelity.has_value(), w + "fidelity", where) ||
        Differ(x.moves.has_value(), y.moves.has_value(), w + "moves", where) ||
        (x.moves && Differ(*x.moves == *y.moves, true, w + "move statistics", where)) ||
        Differ(x.particles.size(), y.particles.size(), w + "particle count", where)) {
      return false;
    }
    if (x.multi_fidelity) {
      // Not the call seconds: they are not deterministic.
      const auto& f = *x.multi_fidelity;
      const auto& g = *y.multi_fidelity;
      if (Differ(f.continue_if_accepted, g.continue_if_accepted, w + "eta_1", where) ||
          Differ(f.continue_if_rejected, g.continue_if_rejected, w + "eta_2", where) ||
          Differ(f.expensive_simulations,
                 g.expensive_simulations,
                 w + "expensive_simulations",
                 where) ||
          Differ(
              f.next_continue_if_accepted, g.next_continue_if_accepted, w + "next eta_1", where) ||
          Differ(
              f.next_continue_if_rejected, g.next_continue_if_rejected, w + "next eta_2", where) ||
          Differ(f.cost_ratio, g.cost_ratio, w + "cost_ratio", where) ||
          Differ(f.unkept_false_positives,
                 g.unkept_false_positives,
                 w + "unkept_false_positives",
                 where) ||
          Differ(f.unkept_false_positive_log_w2,
                 g.unkept_false_positive_log_w2,
                 w + "unkept_false_positive_log_w2",
                 where)) {
        return false;
      }
    }
    for (std::size_t i = 0; i < x.particles.size(); ++i) {
      const auto& p = x.particles[i];
      const auto& q = y.particles[i];
      const std::string pi = w + "particle " + std::to_string(i) + ": ";
      if (Differ(p.index, q.index, pi + "index", where) ||
          Differ(p.theta.bits, q.theta.bits, pi + "bits", where) ||
          Differ(p.theta.reals, q.theta.reals, pi + "reals", where) ||
          Differ(p.log_weight, q.log_weight, pi + "log_weight", where) ||
          Differ(p.weight, q.weight, pi + "weight", where) ||
          Differ(p.multiplier, q.multiplier, pi + "multiplier", where) ||
          Differ(p.low_distance, q.low_distance, pi + "low_distance", where) ||
          Differ(p.confirmed, q.confirmed, pi + "confirmed", where) ||
          Differ(p.distance, q.distance, pi + "distance", where) ||
          Differ(p.output, q.output, pi + "output", where) ||
          Differ(p.ancestor, q.ancestor, pi + "ancestor", where)) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace combabc
