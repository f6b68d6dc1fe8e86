#pragma once
// The joint sampler's model probabilities (docs/algorithm.md, "Model choice", method "joint"),
// read off a run over the joint space of simulators/model_switch.hpp. Private to src/services.
#include <cstddef>
#include <vector>

#include "combabc/samplers/monte_carlo_error.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/services/model_choice.hpp"
#include "simulators/model_switch.hpp"

namespace combabc {

// P(M_k | D) from a wave: the weighted mass of the particles whose indicator says k, with
// WeightedProbability's delta-method error (a resample-move wave's clustered by parent and by Eve,
// the larger), floored by the rule of three at the wave's ESS. A model with no particle is
// reported with an upper bound only: that floor, min(3 / ESS, 0.5). A wave without particles
// gives every model NaN.
std::vector<ModelProbability> JointModelProbabilities(const WaveRecord& wave,
                                                      const JointLayout& layout);

// Model k's own bits given the model: P(bit = 1 | M_k, D) per bit of model k, in its order, from
// the particles of that model (their weights renormalised; errors as WaveMonteCarloErrors'). Empty
// when no particle has model k.
std::vector<WeightedMoment> JointModelBits(const WaveRecord& wave,
                                           const JointLayout& layout,
                                           std::size_t model);

}  // namespace combabc
