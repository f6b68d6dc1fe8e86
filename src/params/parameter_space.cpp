#include "combabc/params/parameter_space.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc {

namespace {

std::string Written(double x) {
  std::array<char, 32> buf{};
  const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return {buf.data(), result.ptr};
}

std::string Field(std::size_t k, const std::string& name) {
  return "reals[" + std::to_string(k) + "] (" + name + ")";
}

}  // namespace

RealsPrior::RealsPrior(std::vector<ContinuousPrior> marginals,
                       std::vector<std::string> names,
                       std::vector<Group> groups)
    : marginals_(std::move(marginals)),
      names_(std::move(names)),
      groups_(std::move(groups)),
      group_of_(marginals_.size(), -1) {
  COMBABC_CHECK(names_.size() == marginals_.size());
  for (std::size_t g = 0; g < groups_.size(); ++g) {
    for (const std::size_t k : groups_[g].index) group_of_[k] = static_cast<int>(g);
  }
}

std::span<const double> RealsPrior::Gather(const Group& g,
                                           std::span<const double> reals,
                                           std::vector<double>& scratch) const {
  bool contiguous = true;
  for (std::size_t i = 1; i < g.index.size(); ++i) {
    contiguous = contiguous && g.index[i] == g.index[0] + i;
  }
  if (contiguous) return reals.subspan(g.index[0], g.index.size());
  scratch.clear();
  for (const std::size_t k : g.index) scratch.push_back(reals[k]);
  return scratch;
}

double RealsPrior::LogDensity(std::span<const double> reals) const {
  COMBABC_CHECK(reals.size() == marginals_.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < reals.size(); ++k) {
    if (group_of_[k] >= 0) {
      if (!marginals_[k].InSupport(reals[k])) return -std::numeric_limits<double>::infinity();
    } else {
      sum += marginals_[k].LogDensity(reals[k]);
    }
  }
  std::vector<double> scratch;
  for (const Group& g : groups_) sum += g.prior->LogDensity(Gather(g, reals, scratch));
  return sum;
}

bool RealsPrior::InSupport(std::span<const double> reals) const {
  COMBABC_CHECK(reals.size() == marginals_.size());
  for (std::size_t k = 0; k < reals.size(); ++k) {
    if (!marginals_[k].InSupport(reals[k])) return false;
  }
  // A joint density may vanish inside the bounds (a constraint between its reals).
  std::vector<double> scratch;
  for (const Group& g : groups_) {
    if (!(g.prior->LogDensity(Gather(g, reals, scratch)) >
          -std::numeric_limits<double>::infinity())) {
      return false;
    }
  }
  return true;
}

void RealsPrior::Sample(RandomStream& rng, std::span<double> reals) const {
  COMBABC_CHECK(reals.size() == marginals_.size());
  std::vector<double> draw;
  for (std::size_t k = 0; k < reals.size(); ++k) {
    if (group_of_[k] < 0) {
      reals[k] = marginals_[k].Sample(rng);
      continue;
    }
    const Group& g = groups_[static_cast<std::size_t>(group_of_[k])];
    if (g.index.front() != k) continue;  // drawn with its group's first real
    draw.assign(g.index.size(), 0.0);
    g.prior->Sample(rng, draw);
    for (std::size_t i = 0; i < g.index.size(); ++i) {
      const std::size_t j = g.index[i];
      if (!marginals_[j].InSupport(draw[i])) {
        throw Error(ErrorKind::kConfig,
                    "prior: the sampler drew " + Written(draw[i]) + ", outside the support [" +
                        Written(marginals_[j].low) + ", " + Written(marginals_[j].high) + "]",
                    "",
                    0,
                    Field(j, names_[j]));
      }
      reals[j] = draw[i];
    }
  }
}

ParameterSpace::ParameterSpace(BinarySpace bits,
                               std::vector<ContinuousParameter> reals,
                               std::vector<JointPriorGroup> joint)
    : bits_(std::move(bits)), reals_(std::move(reals)), joint_(std::move(joint)) {
  // Zero bits is a continuous-only space; zero of both has nothing to infer.
  if (bits_.dimension() == 0 && reals_.empty()) {
    throw Error(ErrorKind::kConfig,
                "the space has no parameters: declare at least one bit or one real parameter");
  }
  // Bit names share the namespace: histories, exports and reports name every parameter, so a real
  // called like a bit would make them ambiguous.
  std::set<std::string> bit_names;
  for (int bit = 0; bit < bits_.dimension(); ++bit) bit_names.insert(bits_.name(bit));
  std::set<std::string> seen;
  for (std::size_t k = 0; k < reals_.size(); ++k) {
    const ContinuousParameter& p = reals_[k];
    const std::string field = Field(k, p.name);
    if (p.name.empty()) {
      throw Error(ErrorKind::kConfig, "name is empty; every parameter needs a name", "", 0, field);
    }
    if (!seen.insert(p.name).second) {
      throw Error(
          ErrorKind::kConfig,
          "name '" + p.name + "' is used by an earlier real parameter; names must be unique",
          "",
          0,
          field);
    }
    if (bit_names.contains(p.name)) {
      throw Error(ErrorKind::kConfig,
                  "name '" + p.name + "' is also a bit's name; names must be unique",
                  "",
                  0,
                  field);
    }
    std::string why;
    if (!p.prior.IsValid(&why)) {
      throw Error(
          ErrorKind::kConfig, std::string(ToString(p.prior.kind)) + " prior: " + why, "", 0, field);
    }
  }
  CheckJointPriors();
  // Precomputed once: LogPriorBits runs for every candidate of every wave.
  for (const double p : bits_.free_prior_one()) {
    log_density_.push_back(std::log1p(-p));
    log_density_.push_back(std::log(p));
  }
}

double ParameterSpace::LogPriorBits(std::span<const std::uint8_t> free_bits) const {
  COMBABC_CHECK(2 * free_bits.size() == log_density_.size());
  double sum = 0.0;
  for (std::size_t j = 0; j < free_bits.size(); ++j) {
    sum += log_density_[2 * j + (free_bits[j] & 1U)];
  }
  return sum;
}

void ParameterSpace::CheckJointPriors() {
  std::vector<int> group_of(reals_.size(), -1);
  std::vector<RealsPrior::Group> groups;
  for (std::size_t g = 0; g < joint_.size(); ++g) {
    const JointPriorGroup& group = joint_[g];
    std::string field = "joint[" + std::to_string(g) + "] (";
    for (std::size_t i = 0; i < group.names.size(); ++i) {
      field += (i ? ", " : "") + group.names[i];
    }
    field += ")";
    auto fail = [&](const std::string& why) { throw Error(ErrorKind::kConfig, why, "", 0, field); };
    if (!group.prior) fail("no prior given");
    if (group.names.empty()) fail("names no parameter; a joint prior covers at least one");
    if (static_cast<int>(group.names.size()) != group.prior->dimension()) {
      fail("names " + std::to_string(group.names.size()) + " parameters but the prior has " +
           std::to_string(group.prior->dimension()) + " dimensions");
    }
    RealsPrior::Group indexed{{}, group.prior};
    std::vector<std::string> names;
    std::vector<double> low, high;
    for (const std::string& name : group.names) {
      const auto it = std::find_if(reals_.begin(), reals_.end(), [&](const ContinuousParameter& p) {
        return p.name == name;
      });
      if (it == reals_.end()) fail("no real parameter is called '" + name + "'");
      const auto k = static_cast<std::size_t>(it - reals_.begin());
      if (it->prior.kind != PriorKind::kJoint) {
        fail("'" + name + "' has a " + std::string(ToString(it->prior.kind)) +
             " prior of its own; a real under a joint prior declares prior kind joint");
      }
      if (group_of[k] >= 0) {
        fail("'" + name + "' is already under joint[" + std::to_string(group_of[k]) +
             "]; a real has one prior");
      }
      group_of[k] = static_cast<int>(g);
      indexed.index.push_back(k);
      names.push_back(Field(k, name));
      low.push_back(it->prior.low);
      high.push_back(it->prior.high);
    }
    // Restricted to its reals' bounds (a normal truncated there), then checked as drawn.
    indexed.prior = RestrictJointPrior(group.prior, names, low, high);
    const JointPriorMoments moments = CheckJointPrior(*indexed.prior, names, low, high);
    for (std::size_t i = 0; i < indexed.index.size(); ++i) {
      ContinuousPrior& prior = reals_[indexed.index[i]].prior;
      prior.mean = moments.mean[i];
      prior.sd = moments.sd[i];
    }
    groups.push_back(std::move(indexed));
  }
  std::vector<ContinuousPrior> marginals;
  std::vector<std::string> names;
  for (std::size_t k = 0; k < reals_.size(); ++k) {
    if (reals_[k].prior.kind == PriorKind::kJoint && group_of[k] < 0) {
      throw Error(ErrorKind::kConfig,
                  "prior kind joint, but no joint prior covers it",
                  "",
                  0,
                  Field(k, reals_[k].name));
    }
    marginals.push_back(reals_[k].prior);
    names.push_back(reals_[k].name);
  }
  reals_prior_ = RealsPrior(std::move(marginals), std::move(names), std::move(groups));
}

}  // namespace combabc
