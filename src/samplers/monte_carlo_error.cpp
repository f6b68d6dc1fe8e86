// Delta-method standard errors of self-normalised weighted estimates (monte_carlo_error.hpp).
#include "combabc/samplers/monte_carlo_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "combabc/core/check.hpp"

namespace combabc {
namespace {

// (sum w)^2 / sum w^2: the weights' ESS (1 / sum w^2 once normalised).
double WeightsEss(std::span<const double> weights) {
  double sum = 0.0;
  double squares = 0.0;
  for (const double w : weights) {
    sum += w;
    squares += w * w;
  }
  return squares > 0.0 ? sum * sum / squares : 0.0;
}

// The estimate whose influence terms are `influence` (f_i - mu for a mean): se =
// sqrt(sum w^2 psi^2) / sum w, and n_f = spread / se^2.
// With `clusters` (a dense cluster number per particle), the terms w psi of one cluster are summed
// before squaring (Chan & Lai 2013): particles that share an ancestor are not independent draws.
WeightedMoment FromInfluence(std::span<const double> weights,
                             std::span<const double> influence,
                             double value,
                             double spread,
                             std::span<const std::size_t> clusters) {
  double sum = 0.0;
  double squares = 0.0;
  if (clusters.empty()) {
    for (std::size_t i = 0; i < weights.size(); ++i) {
      sum += weights[i];
      squares += weights[i] * weights[i] * influence[i] * influence[i];
    }
  } else {
    COMBABC_CHECK(clusters.size() == weights.size());
    std::vector<double> term(*std::max_element(clusters.begin(), clusters.end()) + 1, 0.0);
    for (std::size_t i = 0; i < weights.size(); ++i) {
      sum += weights[i];
      term[clusters[i]] += weights[i] * influence[i];
    }
    for (const double t : term) squares += t * t;
  }
  WeightedMoment m;
  m.value = value;
  if (!(sum > 0.0)) {
    m.se = std::numeric_limits<double>::infinity();
    return m;
  }
  m.se = std::sqrt(squares) / sum;
  m.ess = m.se > 0.0 ? spread / (m.se * m.se) : WeightsEss(weights);
  return m;
}

}  // namespace

WeightedMoment WeightedMean(std::span<const double> weights,
                            std::span<const double> values,
                            std::span<const std::size_t> clusters) {
  COMBABC_CHECK(weights.size() == values.size());
  double sum = 0.0;
  double first = 0.0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    sum += weights[i];
    first += weights[i] * values[i];
  }
  const double mean = sum > 0.0 ? first / sum : 0.0;
  std::vector<double> influence(values.size());
  double spread = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    influence[i] = values[i] - mean;
    spread += weights[i] * influence[i] * influence[i];
  }
  return FromInfluence(
      weights, influence, mean, sum > 0.0 ? std::max(0.0, spread / sum) : 0.0, clusters);
}

double ClusterEss(std::span<const double> weights, std::span<const std::size_t> clusters) {
  if (clusters.empty()) return WeightsEss(weights);
  std::vector<double> total(*std::max_element(clusters.begin(), clusters.end()) + 1, 0.0);
  for (std::size_t i = 0; i < weights.size(); ++i) total[clusters[i]] += weights[i];
  return WeightsEss(total);
}

double ProbabilityEss(std::span<const double> weights, bool heavy_particles) {
  double ess = WeightsEss(weights);
  if (heavy_particles) {
    double sum = 0.0;
    double heaviest = 0.0;
    for (const double w : weights) {
      sum += w;
      heaviest = std::max(heaviest, std::abs(w));
    }
    if (heaviest > 0.0) ess = std::min(ess, sum / heaviest);
  }
  return ess;
}

WeightedMoment BoundProbability(WeightedMoment m, double ess) {
  const double clamped = std::clamp(m.value, 0.0, 1.0);
  // Weights that cancel (signed sum <= 0) keep their infinite error.
  if (std::isfinite(m.se)) {
    const double floor = ess > 0.0 ? std::min(kRuleOfThree / ess, 0.5) : 0.5;
    const double edge = std::min(clamped, 1.0 - clamped);
    m.se = std::max({m.se, floor - edge, std::abs(m.value - clamped)});
  }
  m.value = clamped;
  return m;
}

WeightedMoment WeightedProbability(std::span<const double> weights,
                                   std::span<const double> indicator,
                                   bool heavy_particles,
                                   std::span<const std::size_t> clusters) {
  const double ess =
      clusters.empty() ? ProbabilityEss(weights, heavy_particles) : ClusterEss(weights, clusters);
  return BoundProbability(WeightedMean(weights, indicator, clusters), ess);
}

WeightedMoment WeightedSd(std::span<const double> weights,
                          std::span<const double> values,
                          std::span<const std::size_t> clusters) {
  const WeightedMoment mean = WeightedMean(weights, values, clusters);
  double sum = 0.0;
  double second = 0.0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    const double d = values[i] - mean.value;
    sum += weights[i];
    second += weights[i] * d * d;
  }
  const double var = sum > 0.0 ? std::max(0.0, second / sum) : 0.0;
  std::vector<double> influence(values.size());
  double spread = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double d = values[i] - mean.value;
    influence[i] = d * d - var;
    spread += weights[i] * influence[i] * influence[i];
  }
  WeightedMoment v = FromInfluence(
      weights, influence, var, sum > 0.0 ? std::max(0.0, spread / sum) : 0.0, clusters);
  WeightedMoment sd;
  sd.value = std::sqrt(var);
  sd.ess = v.ess;
  // se(sd) = se(var) / (2 sd); a constant quantity (sd 0) has se 0 as its variance has.
  sd.se = sd.value > 0.0 ? v.se / (2.0 * sd.value) : v.se;
  return sd;
}

std::vector<std::size_t> AncestorClusters(const WaveRecord& wave, bool eve) {
  std::vector<std::size_t> clusters;
  if (!wave.moves) return clusters;
  std::vector<std::int64_t> ancestors;
  ancestors.reserve(wave.particles.size());
  for (const Particle& p : wave.particles) ancestors.push_back(eve ? p.eve : p.ancestor);
  std::vector<std::int64_t> distinct = ancestors;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  clusters.reserve(ancestors.size());
  for (const std::int64_t a : ancestors) {
    clusters.push_back(static_cast<std::size_t>(
        std::lower_bound(distinct.begin(), distinct.end(), a) - distinct.begin()));
  }
  return clusters;
}

WaveErrors WaveMonteCarloErrors(const WaveRecord& wave, std::span<const double> prior_one) {
  WaveErrors e;
  std::vector<double> weights;
  weights.reserve(wave.particles.size());
  for (const Particle& p : wave.particles) weights.push_back(p.weight);
  if (wave.particles.empty()) return e;
  // A resample-move wave's particles of one parent, or of one Eve, are correlated: the larger of
  // the two clustered errors (the Eve's sees a mode's share fixed waves ago, but degenerates to
  // 0 once every particle has one Eve; the parent's sees this wave's duplicates).
  const std::vector<std::size_t> clusters = AncestorClusters(wave, false);
  const std::vector<std::size_t> eves = AncestorClusters(wave, true);
  auto wider = [&](WeightedMoment m, const WeightedMoment& by_eve) {
    if (by_eve.se > m.se) {
      m.ess *= (m.se * m.se) / (by_eve.se * by_eve.se);
      m.se = by_eve.se;
    }
    return m;
  };
  const std::size_t bits = wave.particles.front().theta.bits.size();
  const std::size_t reals = wave.particles.front().theta.reals.size();
  std::vector<double> values(weights.size());
  for (std::size_t b = 0; b < bits; ++b) {
    bool varies = false;
    for (std::size_t i = 0; i < values.size(); ++i) {
      values[i] = wave.particles[i].theta.bits[b] != 0 ? 1.0 : 0.0;
      varies = varies || values[i] != values[0];
    }
    e.bits.push_back(
        WeightedProbability(weights, values, wave.multi_fidelity.has_value(), clusters));
    if (!eves.empty()) e.bits.back() = wider(e.bits.back(), WeightedMean(weights, values, eves));
    // A bit the prior fixes: its posterior is the prior's 0 or 1, with no error to floor.
    if (b < prior_one.size() && (prior_one[b] == 0.0 || prior_one[b] == 1.0)) {
      e.bits.back().se = 0.0;
    }
    if (varies) e.bits_ess = std::min(e.bits_ess.value_or(e.bits.back().ess), e.bits.back().ess);
  }
  for (std::size_t r = 0; r < reals; ++r) {
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = wave.particles[i].theta.reals[r];
    e.real_means.push_back(WeightedMean(weights, values, clusters));
    e.real_sds.push_back(WeightedSd(weights, values, clusters));
    if (!eves.empty()) {
      e.real_means.back() = wider(e.real_means.back(), WeightedMean(weights, values, eves));
      e.real_sds.back() = wider(e.real_sds.back(), WeightedSd(weights, values, eves));
    }
  }
  return e;
}

}  // namespace combabc
