#pragma once
// The joint sampler of a model choice (docs/algorithm.md, "Model choice", method "joint"): one
// run over a product space, the model indicator and the models' parameters, so that the
// combinatorial SMC samples models and parameters together, unchanged (threads, ranks, resume,
// noise-aware acceptance, experiments, resample-move hold as for any run).
//  - The indicator is K - 1 stick-breaking bits b_1..b_{K-1}: the model is the first k with
//    b_k = 1, else K, and P(b_k = 1) = pi_k / (1 - pi_1 - ... - pi_{k-1}), which gives model k
//    the prior pi_k while the prior stays a product of independent bits (what the binary
//    proposal needs). The bits after the first 1 are ignored by the simulator and stay at their
//    prior. The binary proposal is then the model-jump kernel. The joint method's default, the
//    ancestor kernel, keeps every model's proposal probability at least 0.05 pi_k (its defensive
//    prior); a product kernel fitted without a floor proposes a model that has lost its last
//    particle with probability 0 unless mixture tempering (phi > 0) mixes the prior back in
//    (docs/algorithm.md, "Model choice").
//  - Models with identical parameters (names and priors) share them: then each particle's
//    parameters are those of its model. Otherwise each model's parameters appear once per model,
//    named "<model>.<name>"; a model's parameters are ignored while another model is active, so
//    there their posterior is their prior (a pseudo-prior), which the importance weights make
//    exact.
// Private to src (the problem builder in src/services builds it; tests use it directly).
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc {

// One candidate model's parameters, as its config gives them.
struct ModelParameters {
  BinarySpaceOptions bits;
  std::vector<ContinuousParameter> reals;
  std::vector<JointPriorGroup> joint;
};

// Where model k's parameters sit in the joint value.
struct JointLayout {
  std::vector<std::string> names;       // the models'
  std::vector<double> prior;            // pi_k
  bool shared = false;                  // every model has the same parameters
  std::vector<std::vector<int>> bits;   // per model: its bits' joint indices, in its order
  std::vector<std::vector<int>> reals;  // per model: its reals' joint indices
  int indicator_bits() const { return static_cast<int>(prior.size()) - 1; }
  // The model of a joint bit vector (stick-breaking: the first indicator bit set).
  std::size_t ModelOf(std::span<const std::uint8_t> joint_bits) const;
};

struct JointSpace {
  ParameterSpace space;
  JointLayout layout;
};

// Throws combabc::Error(kConfig) for fewer than two models, priors not positive, or joint priors
// over reals of models that do not share their parameters (not supported).
JointSpace BuildJointSpace(const std::vector<std::string>& names,
                           const std::vector<double>& prior,
                           const std::vector<ModelParameters>& models);

// Simulates a joint value with its model's simulator, on that model's own bits and reals. All
// models give the same outputs (checked by the caller: the same experiments and coordinates).
class ModelSwitch : public Simulator {
 public:
  ModelSwitch(std::vector<std::unique_ptr<Simulator>> models, JointLayout layout);
  int output_size() const override { return models_.front()->output_size(); }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  // The batch split by model, each part handed to its model's own batch form (the sensor's
  // batched solve, an external simulator's worker pool).
  void SimulateBatch(const ParameterBatch& batch,
                     std::span<RandomStream> rngs,
                     std::span<double> out,
                     BatchFailures& failures) const override;

 private:
  std::vector<std::unique_ptr<Simulator>> models_;
  JointLayout layout_;
};

}  // namespace combabc
