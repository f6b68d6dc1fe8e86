#include "simulators/model_switch.hpp"

#include <algorithm>
#include <cstddef>
#include <utility>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

// Every bit's prior P(1), the options' default filled in.
std::vector<double> PriorOne(const BinarySpaceOptions& o) {
  return o.prior_one.empty()
             ? std::vector<double>(static_cast<std::size_t>(o.dimension), o.default_prior_one)
             : o.prior_one;
}

bool SamePrior(const ContinuousPrior& a, const ContinuousPrior& b) {
  return a.kind == b.kind && a.low == b.low && a.high == b.high && a.mean == b.mean && a.sd == b.sd;
}

// Identical parameters: the same bits (names, priors, ties) and reals (names, priors, groups).
bool SameParameters(const ModelParameters& a, const ModelParameters& b) {
  if (a.bits.dimension != b.bits.dimension || PriorOne(a.bits) != PriorOne(b.bits) ||
      a.bits.tied != b.bits.tied ||
      BinarySpace(a.bits).dimension() != BinarySpace(b.bits).dimension()) {
    return false;
  }
  const BinarySpace sa(a.bits);
  const BinarySpace sb(b.bits);
  for (int k = 0; k < sa.dimension(); ++k) {
    if (sa.name(k) != sb.name(k)) return false;
  }
  if (a.reals.size() != b.reals.size() || a.joint.size() != b.joint.size()) return false;
  for (std::size_t k = 0; k < a.reals.size(); ++k) {
    if (a.reals[k].name != b.reals[k].name || !SamePrior(a.reals[k].prior, b.reals[k].prior)) {
      return false;
    }
  }
  for (std::size_t g = 0; g < a.joint.size(); ++g) {
    if (a.joint[g].names != b.joint[g].names) return false;
  }
  return true;
}

}  // namespace

std::size_t JointLayout::ModelOf(std::span<const std::uint8_t> joint_bits) const {
  const std::size_t indicators = prior.size() - 1;
  for (std::size_t k = 0; k < indicators; ++k) {
    if (joint_bits[k] != 0) return k;
  }
  return indicators;
}

JointSpace BuildJointSpace(const std::vector<std::string>& names,
                           const std::vector<double>& prior,
                           const std::vector<ModelParameters>& models) {
  if (models.size() < 2 || names.size() != models.size() || prior.size() != models.size()) {
    throw Error(ErrorKind::kConfig, "a joint model choice needs two or more models, each named");
  }
  JointLayout layout;
  layout.names = names;
  layout.prior = prior;
  BinarySpaceOptions bits;
  // The stick-breaking indicator: P(b_k = 1) = pi_k / (mass left after models 1..k-1).
  double left = 1.0;
  for (std::size_t k = 0; k + 1 < models.size(); ++k) {
    if (!(prior[k] > 0.0)) {
      throw Error(ErrorKind::kConfig,
                  "model \"" + names[k] +
                      "\" has prior 0: the joint sampler needs every model's prior above 0");
    }
    bits.prior_one.push_back(std::min(1.0, prior[k] / left));
    bits.names.push_back("model " + names[k]);
    left -= prior[k];
  }
  layout.shared = true;
  for (const ModelParameters& m : models) {
    layout.shared = layout.shared && SameParameters(m, models.front());
  }
  std::vector<ContinuousParameter> reals;
  std::vector<JointPriorGroup> joint;
  const std::size_t copies = layout.shared ? 1 : models.size();
  for (std::size_t c = 0; c < copies; ++c) {
    const ModelParameters& m = models[c];
    const BinarySpace space(m.bits);
    const std::string prefix = layout.shared ? "" : names[c] + ".";
    const auto offset = static_cast<int>(bits.prior_one.size());
    const std::vector<double> one = PriorOne(m.bits);
    std::vector<int> bit_index;
    std::vector<int> real_index;
    for (int b = 0; b < space.dimension(); ++b) {
      bits.prior_one.push_back(one[static_cast<std::size_t>(b)]);
      bits.names.push_back(prefix + space.name(b));
      bit_index.push_back(offset + b);
    }
    for (std::vector<int> group : m.bits.tied) {
      for (int& b : group) b += offset;
      bits.tied.push_back(std::move(group));
    }
    if (!layout.shared && !m.joint.empty()) {
      throw Error(ErrorKind::kConfig,
                  "model \"" + names[c] +
                      "\" has a joint prior over reals, and the models' parameters differ: the "
                      "joint sampler supports joint priors only over parameters all models share");
    }
    for (const ContinuousParameter& r : m.reals) {
      real_index.push_back(static_cast<int>(reals.size()));
      reals.push_back({prefix + r.name, r.prior});
    }
    joint = m.joint;
    layout.bits.push_back(std::move(bit_index));
    layout.reals.push_back(std::move(real_index));
  }
  if (layout.shared) {
    layout.bits.resize(models.size(), layout.bits.front());
    layout.reals.resize(models.size(), layout.reals.front());
  }
  bits.dimension = static_cast<int>(bits.prior_one.size());
  ParameterSpace space(BinarySpace(bits), std::move(reals), std::move(joint));
  return {std::move(space), std::move(layout)};
}

ModelSwitch::ModelSwitch(std::vector<std::unique_ptr<Simulator>> models, JointLayout layout)
    : models_(std::move(models)), layout_(std::move(layout)) {}

void ModelSwitch::Simulate(const ParameterView& theta,
                           RandomStream& rng,
                           std::span<double> out) const {
  const std::size_t k = layout_.ModelOf(theta.bits);
  std::vector<std::uint8_t> bits;
  std::vector<double> reals;
  for (const int b : layout_.bits[k]) bits.push_back(theta.bits[static_cast<std::size_t>(b)]);
  for (const int r : layout_.reals[k]) reals.push_back(theta.reals[static_cast<std::size_t>(r)]);
  models_[k]->Simulate({bits, reals}, rng, out);
}

void ModelSwitch::SimulateBatch(const ParameterBatch& batch,
                                std::span<RandomStream> rngs,
                                std::span<double> out,
                                BatchFailures& failures) const {
  const auto width = static_cast<std::size_t>(output_size());
  for (std::size_t k = 0; k < models_.size(); ++k) {
    std::vector<std::size_t> mine;
    for (std::size_t i = 0; i < batch.count; ++i) {
      if (layout_.ModelOf(batch[i].bits) == k) mine.push_back(i);
    }
    if (mine.empty()) continue;
    const std::size_t nb = layout_.bits[k].size();
    const std::size_t nr = layout_.reals[k].size();
    std::vector<std::uint8_t> bits;
    std::vector<double> reals;
    std::vector<RandomStream> streams;
    bits.reserve(mine.size() * nb);
    reals.reserve(mine.size() * nr);
    streams.reserve(mine.size());
    for (const std::size_t i : mine) {
      const ParameterView theta = batch[i];
      for (const int b : layout_.bits[k]) bits.push_back(theta.bits[static_cast<std::size_t>(b)]);
      for (const int r : layout_.reals[k]) {
        reals.push_back(theta.reals[static_cast<std::size_t>(r)]);
      }
      streams.push_back(rngs[i]);
    }
    ParameterBatch part;
    part.count = mine.size();
    part.num_bits = nb;
    part.num_reals = nr;
    part.bits = bits;
    part.reals = reals;
    std::vector<double> results(mine.size() * width);
    std::vector<std::uint8_t> status(mine.size(), 0);
    std::vector<char> reasons(mine.size() * kFailureReasonBytes, '\0');
    BatchFailures part_failures(status, reasons);
    models_[k]->SimulateBatch(part, streams, results, part_failures);
    for (std::size_t j = 0; j < mine.size(); ++j) {
      const std::size_t i = mine[j];
      rngs[i] = streams[j];
      if (part_failures.failed(j)) failures.Fail(i, part_failures.reason(j));
      for (std::size_t o = 0; o < width; ++o) out[i * width + o] = results[j * width + o];
    }
  }
}

}  // namespace combabc
