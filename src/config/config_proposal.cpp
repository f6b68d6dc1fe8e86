// [proposal] (the kernels: ProposalOptions), [parameters.<name>] (continuous unknowns of the
// model with their priors) and [[joint_prior]] (a correlated Gaussian over some of them).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/params/parameter_space.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Names() {
  std::string out;
  for (const auto& p : plate::kSensorVariationFields) {
    out += out.empty() ? "\"" : ", \"";
    out += p.name;
    out += "\"";
  }
  return out;
}

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

ContinuousPrior ParsePrior(TableReader& t, const plate::SensorVariationField& info) {
  ContinuousPrior prior;
  const auto kind = t.Choice<PriorKind>("prior", "prior");
  if (!kind) {
    t.Fail("prior",
           "missing required key: one of \"uniform\", \"normal\", \"lognormal\", "
           "\"truncated_normal\", \"joint\"");
  }
  prior.kind = *kind;
  if (prior.kind == PriorKind::kJoint) {
    // A coordinate of a [[joint_prior]]: low and high bound its support (default: the physical
    // range), which the joint prior's sampler must respect.
    for (const char* key : {"mean", "sd"}) {
      if (t.Has(key)) t.Fail(key, "not used by prior = \"joint\" (the [[joint_prior]] has it)");
    }
    prior.low = t.Number("low").value_or(info.low);
    prior.high = t.Number("high").value_or(info.high);
    if (!(prior.low < prior.high)) t.Fail("high", "must be above low = " + Num(prior.low));
    if (prior.low < info.low || prior.high > info.high) {
      t.Fail(prior.low < info.low ? "low" : "high",
             "the support [" + Num(prior.low) + ", " + Num(prior.high) + "] must lie within " +
                 std::string(info.name) + "'s physical range [" + Num(info.low) + ", " +
                 Num(info.high) + "]");
    }
    return prior;
  }
  const bool bounded =
      prior.kind == PriorKind::kUniform || prior.kind == PriorKind::kTruncatedNormal;
  auto number = [&](const char* key, bool wanted) -> double {
    if (!wanted) {
      if (t.Has(key)) {
        t.Fail(key, "not used by prior = \"" + std::string(ToString(prior.kind)) + "\"");
      }
      return 0.0;
    }
    const auto v = t.Number(key);
    if (!v) {
      t.Fail(key, "missing required key for prior = \"" + std::string(ToString(prior.kind)) + "\"");
    }
    if (!std::isfinite(*v)) t.Fail(key, "must be finite");
    return *v;
  };
  prior.low = number("low", bounded);
  prior.high = number("high", bounded);
  prior.mean = number("mean", prior.kind != PriorKind::kUniform);
  prior.sd = number("sd", prior.kind != PriorKind::kUniform);
  if (bounded && !(prior.low < prior.high)) t.Fail("high", "must be above low = " + Num(prior.low));
  if (prior.kind != PriorKind::kUniform && !(prior.sd > 0.0)) t.Fail("sd", "must be > 0");
  // The prior's own check (the interval's width, the lognormal's moments, the truncated normal's
  // mass): at the prior key, since it weighs several keys together.
  if (ValidationError error; !prior.IsValid(&error)) t.Fail("prior", error.Message());
  // The prior may only propose physically meaningful values: its support, or for the unbounded
  // normal and lognormal the interval holding all but 1e-12 of its mass (mean +- 7.1 sd), must lie
  // within the parameter's physical range.
  constexpr double kTail = 7.1;
  double lo = prior.low, hi = prior.high;
  if (prior.kind == PriorKind::kNormal) {
    lo = prior.mean - kTail * prior.sd;
    hi = prior.mean + kTail * prior.sd;
  } else if (prior.kind == PriorKind::kLogNormal) {
    lo = std::exp(prior.mean - kTail * prior.sd);
    hi = std::exp(prior.mean + kTail * prior.sd);
  }
  if (lo < info.low || hi > info.high) {
    t.Fail(bounded ? (lo < info.low ? "low" : "high") : "prior",
           std::string(bounded ? "the prior's support [" : "the prior's mass (all but 1e-12) [") +
               Num(lo) + ", " + Num(hi) + "] must lie within " + std::string(info.name) +
               "'s physical range [" + Num(info.low) + ", " + Num(info.high) + "]" +
               (bounded ? "" : "; narrow it, or use a uniform or truncated_normal prior"));
  }
  return prior;
}

}  // namespace

void ParseProposalSection(TableReader& root, CalibrationConfig* c) {
  auto t = root.Table("proposal");
  if (!t) return;
  ProposalOptions& p = c->smc.proposal;
  p.binary = t->Choice<BinaryKernelKind>("kind", "proposal kind").value_or(p.binary);
  LogisticKernelOptions& l = p.logistic;
  const bool logistic = p.binary == BinaryKernelKind::kLogistic;
  for (const char* key : {"min_correlation", "max_predecessors", "ridge", "min_marginal", "clip"}) {
    if (!logistic && t->Has(key)) t->Fail(key, "only used with kind = \"logistic\"");
  }
  l.min_correlation = t->NumberIn("min_correlation", l.min_correlation, 0.0, 0.999);
  l.max_predecessors = t->IntegerIn("max_predecessors", l.max_predecessors, 0, 4096);
  l.ridge = t->NumberIn("ridge", l.ridge, 0.0, 1e6);
  l.min_marginal = t->NumberIn("min_marginal", l.min_marginal, 0.0, 0.49);
  l.clip = t->NumberIn("clip", l.clip, 1e-12, 0.1);
  p.continuous =
      t->Choice<ContinuousKernelKind>("continuous", "continuous kernel").value_or(p.continuous);
  if (p.binary == BinaryKernelKind::kAncestor && p.continuous != ContinuousKernelKind::kNormal) {
    t->Fail("continuous", "kind = \"ancestor\" proposes the reals itself (with scale)");
  }
  if (p.continuous != ContinuousKernelKind::kNormal && t->Has("scale")) {
    t->Fail("scale", "only used with continuous = \"normal\"");
  }
  p.scale = t->NumberIn("scale", p.scale, 1e-6, 1e6);
  t->Finish();
}

void ParseParametersSection(TableReader& root, CalibrationConfig* c) {
  const toml::node* node = root.Raw("parameters");
  if (!node) return;
  if (!node->is_table()) {
    root.FailAt(*node,
                "parameters",
                "expected tables [parameters.<name>], got " + std::string(TypeName(*node)));
  }
  auto t = root.Table("parameters");
  for (const auto& [key, value] : *node->as_table()) {
    const std::string name(key.str());
    // An external simulator's parameters are its own: any name, no physical range combabc knows.
    const plate::SensorVariationField any{name.c_str(), nullptr, -kInf, kInf, ""};
    const bool sensor = c->simulator.kind == SimulatorKind::kSensor;
    const plate::SensorVariationField* info = sensor ? plate::FindSensorVariationField(name) : &any;
    if (!info) {
      root.FailAt(value,
                  "parameters." + name,
                  "the sensor model has no continuous parameter " + Excerpt(name) +
                      "; expected one of " + Names());
    }
    if (!value.is_table()) {
      root.FailAt(value, "parameters." + name, "expected a table with prior = \"...\"");
    }
    auto p = t->Table(name);
    c->reals.push_back({name, ParsePrior(*p, *info)});
    p->Finish();
  }
  t->Finish();
}

void ParseJointPriorSection(TableReader& root, CalibrationConfig* c) {
  for (TableReader& t : root.Tables("joint_prior")) {
    JointPriorGroup group;
    group.names = t.Strings("parameters").value_or(std::vector<std::string>{});
    if (group.names.empty()) t.Fail("parameters", "missing required key: the reals it covers");
    for (const std::string& name : group.names) {
      const bool joint = std::any_of(c->reals.begin(), c->reals.end(), [&](const auto& r) {
        return r.name == name && r.prior.kind == PriorKind::kJoint;
      });
      if (!joint) {
        t.Fail("parameters",
               "needs [parameters." + name + "] with prior = \"joint\" for " + Excerpt(name));
      }
    }
    const std::string kind = t.String("kind").value_or("");
    if (kind != "normal") t.Fail("kind", "must be \"normal\" (a correlated Gaussian)");
    const std::vector<double> mean = t.Numbers("mean").value_or(std::vector<double>{});
    if (mean.size() != group.names.size()) {
      t.Fail("mean", "needs one value per parameter (" + std::to_string(group.names.size()) + ")");
    }
    // covariance = [[...], [...]]: one row per parameter.
    std::vector<double> covariance;
    const toml::node* rows = t.Raw("covariance");
    if (!rows || !rows->is_array() || rows->as_array()->size() != mean.size()) {
      t.Fail("covariance",
             "needs one row per parameter: [[...], ...], " + std::to_string(mean.size()) + " x " +
                 std::to_string(mean.size()));
    }
    for (const toml::node& row : *rows->as_array()) {
      if (!row.is_array() || row.as_array()->size() != mean.size()) {
        t.Fail("covariance", "each row needs " + std::to_string(mean.size()) + " numbers");
      }
      for (const toml::node& x : *row.as_array()) {
        const auto v = x.value<double>();
        if (!v) t.Fail("covariance", "holds numbers only");
        covariance.push_back(*v);
      }
    }
    try {
      group.prior = MakeMultivariateNormalPrior(mean, std::move(covariance));
    } catch (const Error& e) {
      t.Fail("covariance", e.message());
    }
    t.Finish();
    c->joint_priors.push_back(std::move(group));
  }
  // The rest (every joint real covered once; the sampler against the density) as the run's space
  // will check it, now, so that the error points at the config.
  if (c->reals.empty()) return;
  try {
    const ParameterSpace check(BinarySpace::Independent(0), c->reals, c->joint_priors);
  } catch (const Error& e) {
    root.Fail(c->joint_priors.empty() ? "parameters" : "joint_prior",
              e.field() + ": " + e.message());
  }
}

}  // namespace combabc::config_internal
