// The joint sampler's model probabilities (src/services/model_joint.hpp).
#include "services/model_joint.hpp"

#include <algorithm>
#include <limits>

namespace combabc {
namespace {

// The wave's particles' weights and, per particle, its model.
struct Split {
  std::vector<double> weights;
  std::vector<std::size_t> model;
};

Split SplitByModel(const WaveRecord& wave, const JointLayout& layout) {
  Split s;
  for (const Particle& p : wave.particles) {
    s.weights.push_back(p.weight);
    s.model.push_back(layout.ModelOf(p.theta.bits));
  }
  return s;
}

// WeightedProbability clustered by parent, widened to the clustering by Eve where that is larger
// (WaveMonteCarloErrors' rule).
WeightedMoment Probability(const WaveRecord& wave,
                           std::span<const double> weights,
                           std::span<const double> indicator) {
  const std::vector<std::size_t> parents = AncestorClusters(wave, false);
  const std::vector<std::size_t> eves = AncestorClusters(wave, true);
  WeightedMoment m = WeightedProbability(weights, indicator, false, parents);
  if (!eves.empty()) {
    const WeightedMoment by_eve = WeightedMean(weights, indicator, eves);
    m.se = std::max(m.se, by_eve.se);
  }
  return m;
}

}  // namespace

std::vector<ModelProbability> JointModelProbabilities(const WaveRecord& wave,
                                                      const JointLayout& layout) {
  std::vector<ModelProbability> out(layout.names.size());
  const Split s = SplitByModel(wave, layout);
  std::vector<double> indicator(s.weights.size());
  for (std::size_t k = 0; k < out.size(); ++k) {
    ModelProbability& p = out[k];
    p.name = layout.names[k];
    p.prior = layout.prior[k];
    if (wave.particles.empty()) {
      p.probability = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    bool any = false;
    for (std::size_t i = 0; i < indicator.size(); ++i) {
      indicator[i] = s.model[i] == k ? 1.0 : 0.0;
      any = any || s.model[i] == k;
    }
    const WeightedMoment m = Probability(wave, s.weights, indicator);
    p.probability = m.value;
    p.se = m.se;
    p.upper = std::min(1.0, m.value + 2.0 * m.se);
    if (!any) {
      // No particle: the rule of three at the wave's ESS, the floor WeightedProbability put in se.
      p.upper_bound_only = true;
      p.upper = m.se;
    }
  }
  return out;
}

std::vector<WeightedMoment> JointModelBits(const WaveRecord& wave,
                                           const JointLayout& layout,
                                           std::size_t model) {
  // The wave restricted to the model's particles, each with its model's own bits: its errors
  // are then those of a wave of that model alone.
  WaveRecord mine;
  mine.moves = wave.moves;
  double total = 0.0;
  for (const Particle& p : wave.particles) {
    if (layout.ModelOf(p.theta.bits) != model) continue;
    Particle q;
    q.index = p.index;
    q.ancestor = p.ancestor;
    q.eve = p.eve;
    q.weight = p.weight;
    for (const int b : layout.bits[model]) {
      q.theta.bits.push_back(p.theta.bits[static_cast<std::size_t>(b)]);
    }
    for (const int r : layout.reals[model]) {
      q.theta.reals.push_back(p.theta.reals[static_cast<std::size_t>(r)]);
    }
    total += p.weight;
    mine.particles.push_back(std::move(q));
  }
  if (mine.particles.empty() || !(total > 0.0)) return {};
  for (Particle& q : mine.particles) q.weight /= total;
  return WaveMonteCarloErrors(mine).bits;
}

}  // namespace combabc
