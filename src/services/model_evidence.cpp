// A model's ABC evidence from its run, and the posterior model probabilities
// (include/combabc/services/model_choice.hpp; docs/algorithm.md, "Model choice").
#include <algorithm>
#include <cmath>
#include <limits>

#include "combabc/core/error.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "combabc/services/model_choice.hpp"

namespace combabc {
namespace {

constexpr double kMinusInf = -std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The log of a candidate's acceptance as the sampler computes it (CombinatorialSmc's LogWeight):
// -inf when a threshold or indicator component rejects d, else -sum_k e_k / T_k over the
// likelihood components, e_k = max(d_k - m_k, 0) with `offsets`, d_k without.
double LogAccept(std::span<const DistanceComponent> components,
                 std::span<const double> d,
                 const std::vector<double>& eps,
                 const std::vector<double>* offsets) {
  double log_accept = 0.0;
  std::size_t s = 0;
  for (std::size_t k = 0; k < components.size(); ++k) {
    switch (components[k].kind) {
      case ComponentKind::kThreshold:
        if (!(d[k] <= eps[s++])) return kMinusInf;
        break;
      case ComponentKind::kIndicator:
        if (d[k] != components[k].required) return kMinusInf;
        break;
      case ComponentKind::kNegLogLikelihood: {
        const double temperature = eps[s];
        const double excess = offsets ? d[k] - (*offsets)[s] : d[k];
        ++s;
        if (std::isinf(temperature)) break;
        if (!(excess < std::numeric_limits<double>::infinity())) return kMinusInf;
        log_accept -= (offsets ? std::max(excess, 0.0) : excess) / temperature;
        break;
      }
    }
  }
  return log_accept;
}

// The sampler's offsets m_k for the wave after `waves` (CombinatorialSmc's OffsetsAfter): per
// likelihood slot the smallest distance among their particles, 0 before any.
std::vector<double> OffsetsAfter(std::span<const DistanceComponent> components,
                                 std::span<const WaveRecord> waves) {
  std::vector<double> offsets;
  for (std::size_t k = 0; k < components.size(); ++k) {
    if (components[k].kind == ComponentKind::kIndicator) continue;
    double best = std::numeric_limits<double>::infinity();
    if (components[k].kind == ComponentKind::kNegLogLikelihood) {
      for (const WaveRecord& w : waves) {
        for (const Particle& p : w.particles) best = std::min(best, p.distance[k]);
      }
    }
    offsets.push_back(std::isfinite(best) ? best : 0.0);
  }
  return offsets;
}

// A wave's evidence: of its own target as the sampler defined it (a rejection wave's with the
// offsets, which the next move wave's reweighting starts from), and of the likelihood without
// offsets at its thresholds (what models are compared by).
struct WaveEvidence {
  bool valid = false;
  double log_target = kMinusInf;
  double log_true = kMinusInf;
  double relative_var = 0.0;         // of the latter
  double target_relative_var = 0.0;  // of the former
};

// log sum exp(x) and log sum exp(2x) over x.
struct LogSums {
  double log_sum = kMinusInf;
  double log_sum2 = kMinusInf;
};
LogSums SumsOf(const std::vector<double>& x) {
  LogSums s;
  if (x.empty()) return s;
  const double top = *std::max_element(x.begin(), x.end());
  if (!std::isfinite(top)) return s;
  double sum = 0.0;
  double sum2 = 0.0;
  for (double v : x) {
    sum += std::exp(v - top);
    sum2 += std::exp(2.0 * (v - top));
  }
  s.log_sum = top + std::log(sum);
  s.log_sum2 = 2.0 * top + std::log(sum2);
  return s;
}

WaveEvidence RejectionWave(const WaveRecord& wave,
                           std::span<const DistanceComponent> components,
                           const std::vector<double>& offsets) {
  WaveEvidence e;
  const auto n_candidates = static_cast<double>(wave.candidates);
  if (wave.candidates <= 0) return e;
  e.valid = true;
  if (wave.particles.empty()) return e;  // evidence 0 at these thresholds
  std::vector<double> log_w;
  std::vector<double> log_y;
  log_w.reserve(wave.particles.size());
  log_y.reserve(wave.particles.size());
  for (const Particle& p : wave.particles) {
    const double with = LogAccept(components, p.distance, wave.thresholds, &offsets);
    const double without = LogAccept(components, p.distance, wave.thresholds, nullptr);
    log_w.push_back(p.log_weight);
    // w L / a: an accepted particle stands for 1 / a candidates like it (Horvitz-Thompson).
    log_y.push_back(with == kMinusInf ? kMinusInf : p.log_weight + without - with);
  }
  const auto n = static_cast<double>(wave.particles.size());
  auto evidence = [&](const std::vector<double>& log_values, double* relative_var) {
    const LogSums s = SumsOf(log_values);
    if (s.log_sum == kMinusInf) return kMinusInf;
    const double log_mean = s.log_sum - std::log(n);
    // var(y) / mean(y)^2 over the accepted: (mean(y^2) / mean(y)^2 - 1) n / (n - 1).
    const double ratio = std::exp(s.log_sum2 - std::log(n) - 2.0 * log_mean) - 1.0;
    const double cv2 = n > 1.0 ? std::max(ratio, 0.0) * n / (n - 1.0) : 0.0;
    if (wave.complete && n >= 2.0 && n_candidates >= 2.0) {
      // Inverse sampling: the wave ran until its n-th acceptance.
      const double p = (n - 1.0) / (n_candidates - 1.0);
      *relative_var = (1.0 - std::min(p, 1.0)) / n + cv2 / n;
      return std::log(p) + log_mean;
    }
    // A fixed number of candidates: Z = sum y / N, var = (sum y^2 / N - Z^2) / N.
    const double log_z = s.log_sum - std::log(n_candidates);
    const double second = std::exp(s.log_sum2 - std::log(n_candidates) - 2.0 * log_z);
    *relative_var = std::max(second - 1.0, 0.0) / n_candidates;
    return log_z;
  };
  e.log_target = evidence(log_w, &e.target_relative_var);
  e.log_true = evidence(log_y, &e.relative_var);
  return e;
}

// Wave t from the wave before: its evidence times the mean incremental weight over its weighted
// particles, sum_i W_i A_t(d_i) / A_{t-1}(d_i), with W_i from the stored p / q (self-normalised,
// so that q's normalising constant cancels). A resample-move wave's target has no offsets; a
// rejection wave's (`offsets`, non-null) has, and its evidence without them is what models are
// compared by: both are estimated.
WaveEvidence ChainedWave(std::span<const WaveRecord> waves,
                         std::size_t t,
                         const WaveEvidence& before,
                         std::span<const DistanceComponent> components,
                         const std::vector<double>* offsets) {
  WaveEvidence e;
  const WaveRecord& previous = waves[t - 1];
  const WaveRecord& wave = waves[t];
  if (!before.valid || previous.particles.empty()) return e;
  e.valid = true;
  const std::vector<double> last_offsets = OffsetsAfter(components, waves.first(t - 1));
  std::vector<double> log_last;
  log_last.reserve(previous.particles.size());
  double top_weight = kMinusInf;
  for (const Particle& p : previous.particles) {
    log_last.push_back(previous.moves
                           ? LogAccept(components, p.distance, previous.thresholds, nullptr)
                           : LogAccept(components, p.distance, previous.thresholds, &last_offsets));
    top_weight = std::max(top_weight, p.log_weight);
  }
  if (top_weight == kMinusInf) return e;
  std::vector<double> weights;
  weights.reserve(previous.particles.size());
  for (const Particle& p : previous.particles) {
    weights.push_back(std::exp(p.log_weight - top_weight));
  }
  const std::vector<std::size_t> clusters = AncestorClusters(previous, false);
  // log sum_i W_i A_t(d_i) / A_{t-1}(d_i) and its relative variance (-inf: no particle in A_t).
  auto factor = [&](const std::vector<double>* next_offsets, double* relative_var) {
    std::vector<double> log_ratio;
    log_ratio.reserve(previous.particles.size());
    double top = kMinusInf;
    for (std::size_t i = 0; i < previous.particles.size(); ++i) {
      const double next =
          LogAccept(components, previous.particles[i].distance, wave.thresholds, next_offsets);
      log_ratio.push_back(log_last[i] == kMinusInf || next == kMinusInf ? kMinusInf
                                                                        : next - log_last[i]);
      top = std::max(top, log_ratio.back());
    }
    if (top == kMinusInf) return kMinusInf;
    std::vector<double> ratios;
    ratios.reserve(log_ratio.size());
    for (double lr : log_ratio) ratios.push_back(lr == kMinusInf ? 0.0 : std::exp(lr - top));
    const WeightedMoment m = WeightedMean(weights, ratios, clusters);
    if (!(m.value > 0.0)) return kMinusInf;
    const double r = m.se / m.value;
    *relative_var = before.target_relative_var + r * r;
    return before.log_target + top + std::log(m.value);
  };
  e.log_true = factor(nullptr, &e.relative_var);
  e.log_target = offsets ? factor(offsets, &e.target_relative_var) : e.log_true;
  if (!offsets) e.target_relative_var = e.relative_var;
  return e;
}

}  // namespace

ModelEvidence EstimateEvidence(const RunHistory& history,
                               std::span<const DistanceComponent> components,
                               const std::vector<double>& final_thresholds) {
  ModelEvidence out;
  out.simulations = history.summary.simulations;
  out.termination = ToString(history.summary.termination);
  const std::span<const WaveRecord> waves(history.waves);
  std::vector<WaveEvidence> evidence(waves.size());
  out.wave_log_evidence.assign(waves.size(), kNaN);
  out.wave_relative_se.assign(waves.size(), kNaN);
  double best_upper = std::numeric_limits<double>::infinity();  // log
  for (std::size_t t = 0; t < waves.size(); ++t) {
    const WaveRecord& wave = waves[t];
    if (wave.multi_fidelity) {
      throw Error(ErrorKind::kUsage,
                  "model choice needs single-fidelity runs: wave " + std::to_string(t + 1) +
                      " is a multi-fidelity wave, whose signed weights estimate no evidence");
    }
    const std::vector<double> offsets = OffsetsAfter(components, waves.first(t));
    if (wave.moves) {
      if (t == 0) continue;
      evidence[t] = ChainedWave(waves, t, evidence[t - 1], components, nullptr);
    } else if (t > 0 && !wave.particles.empty() && !wave.particles[0].theta.reals.empty()) {
      // A proposal over reals is normalised only up to the mass of their support (its draws
      // outside are drawn again: proposal.hpp), a constant of the wave that self-normalised
      // weights do not see but the Horvitz-Thompson mean below would: the evidence is carried
      // from the wave before instead, whose particles the new thresholds reweight.
      evidence[t] = ChainedWave(waves, t, evidence[t - 1], components, &offsets);
    } else {
      evidence[t] = RejectionWave(wave, components, offsets);
    }
    const WaveEvidence& e = evidence[t];
    out.wave_log_evidence[t] = e.valid ? e.log_true : kNaN;
    out.wave_relative_se[t] = e.valid ? std::sqrt(e.relative_var) : kNaN;
    if (!e.valid) continue;
    // Z can only fall as the thresholds tighten (d >= 0 for a likelihood component, so
    // exp(-d / T) falls with T too): every wave's estimate bounds the final evidence.
    if (e.log_true != kMinusInf) {
      best_upper = std::min(best_upper, e.log_true + std::log1p(2.0 * std::sqrt(e.relative_var)));
    } else if (t == 0 && !wave.moves) {
      // None of the prior's N draws was accepted: Z < 3 / N (the rule of three).
      best_upper =
          std::min(best_upper, std::log(kRuleOfThree / static_cast<double>(wave.candidates)));
    }
    if (wave.thresholds == final_thresholds && (wave.complete || !wave.moves)) {
      out.wave = static_cast<int>(t);
      out.reached = e.log_true != kMinusInf;
      out.log_evidence = e.log_true;
      out.relative_se = std::sqrt(e.relative_var);
    }
  }
  if (out.reached) {
    out.log_upper = out.log_evidence + std::log1p(2.0 * out.relative_se);
  } else if (std::isfinite(best_upper)) {
    out.log_upper = best_upper;
  } else {
    out.log_upper = 0.0;  // nothing known: Z <= 1
  }
  return out;
}

std::vector<ModelProbability> ModelProbabilities(std::span<const ModelEvidence> models) {
  std::vector<ModelProbability> out(models.size());
  // log pi_k Z_k of the models with an estimate, for the normaliser.
  double top = kMinusInf;
  for (const ModelEvidence& m : models) {
    if (m.reached && m.prior > 0.0) top = std::max(top, std::log(m.prior) + m.log_evidence);
  }
  double sum = 0.0;
  for (const ModelEvidence& m : models) {
    if (m.reached && m.prior > 0.0) sum += std::exp(std::log(m.prior) + m.log_evidence - top);
  }
  for (std::size_t k = 0; k < models.size(); ++k) {
    const ModelEvidence& m = models[k];
    ModelProbability& p = out[k];
    p.name = m.name;
    p.prior = m.prior;
    if (m.prior <= 0.0) {
      p.probability = 0.0;
      p.upper = 0.0;
      continue;
    }
    if (!m.reached) {
      p.upper_bound_only = true;
      const double mine = std::log(m.prior) + m.log_upper;
      const double scale = std::max(top, mine);
      const double others = top == kMinusInf ? 0.0 : sum * std::exp(top - scale);
      const double own = std::exp(mine - scale);
      p.upper = own / (own + others);
      p.probability = top == kMinusInf ? std::numeric_limits<double>::quiet_NaN() : 0.0;
      continue;
    }
    p.probability = std::exp(std::log(m.prior) + m.log_evidence - top) / sum;
  }
  for (std::size_t k = 0; k < models.size(); ++k) {
    ModelProbability& p = out[k];
    if (p.upper_bound_only || p.prior <= 0.0) continue;
    double var = 0.0;
    for (std::size_t j = 0; j < models.size(); ++j) {
      if (out[j].upper_bound_only || out[j].prior <= 0.0) continue;
      const double r = models[j].relative_se;
      const double dp =
          j == k ? p.probability * (1.0 - p.probability) : p.probability * out[j].probability;
      var += dp * dp * r * r;
    }
    p.se = std::sqrt(var);
    p.upper = std::min(1.0, p.probability + 2.0 * p.se);
  }
  return out;
}

std::vector<std::vector<ModelProbability>> ModelProbabilitiesByWave(
    std::span<const ModelEvidence> models) {
  std::size_t waves = 0;
  for (const ModelEvidence& m : models) waves = std::max(waves, m.wave_log_evidence.size());
  std::vector<std::vector<ModelProbability>> out;
  out.reserve(waves);
  std::vector<ModelEvidence> at(models.begin(), models.end());
  for (std::size_t t = 0; t < waves; ++t) {
    for (std::size_t k = 0; k < models.size(); ++k) {
      const ModelEvidence& m = models[k];
      const std::size_t n = m.wave_log_evidence.size();
      const std::size_t last = n == 0 ? 0 : std::min(t, n - 1);
      const double log_z = n == 0 ? kNaN : m.wave_log_evidence[last];
      at[k].reached = std::isfinite(log_z);
      at[k].log_evidence = at[k].reached ? log_z : kMinusInf;
      at[k].relative_se = at[k].reached ? m.wave_relative_se[last] : 0.0;
      at[k].log_upper = 0.0;  // Z <= 1, used only where there is no estimate
    }
    out.push_back(ModelProbabilities(at));
  }
  return out;
}

}  // namespace combabc
