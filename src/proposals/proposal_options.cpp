#include "combabc/proposals/proposal_options.hpp"

#include <cmath>

#include "combabc/core/error.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/proposals/ancestor_kernel.hpp"
#include "combabc/proposals/logistic_kernel.hpp"

namespace combabc {
namespace {

// The checks shared by LogisticKernelOptions::IsValid and ProposalOptions::IsValid; `owner` and
// `path` name the field ("LogisticKernelOptions" and "", or "ProposalOptions" and "logistic.").
bool LogisticOptionsValid(const LogisticKernelOptions& o,
                          const char* owner,
                          const std::string& path,
                          ValidationError* error) {
  auto fail = [&](const char* field, const std::string& value, const char* constraint) {
    if (error) *error = {owner, path + field, value, constraint};
    return false;
  };
  if (!(o.min_correlation >= 0.0 && o.min_correlation < 1.0)) {
    return fail("min_correlation", std::to_string(o.min_correlation), "must be in [0, 1)");
  }
  if (o.max_predecessors < 0) {
    return fail("max_predecessors", std::to_string(o.max_predecessors), "must be >= 0");
  }
  // ridge = 0 would let a separable regression run its slopes to infinity (it would then fall
  // back to the marginal, losing exactly the strong couplings the kernel exists for).
  if (!(o.ridge > 0.0 && std::isfinite(o.ridge))) {
    return fail("ridge", std::to_string(o.ridge), "must be finite and > 0");
  }
  if (!(o.min_marginal >= 0.0 && o.min_marginal < 0.5)) {
    return fail("min_marginal", std::to_string(o.min_marginal), "must be in [0, 0.5)");
  }
  // clip > 0 keeps q > 0 everywhere (importance weights need the prior's support); clip < 0.5
  // keeps [clip, 1 - clip] a non-degenerate interval.
  if (!(o.clip > 0.0 && o.clip < 0.5)) {
    return fail("clip", std::to_string(o.clip), "must be in (0, 0.5)");
  }
  return true;
}

}  // namespace

bool LogisticKernelOptions::IsValid(ValidationError* error) const {
  return LogisticOptionsValid(*this, "LogisticKernelOptions", "", error);
}

bool LogisticKernelOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool ProposalOptions::IsValid(ValidationError* error) const {
  if (!LogisticOptionsValid(logistic, "ProposalOptions", "logistic.", error)) return false;
  if (!(scale > 0.0 && std::isfinite(scale))) {
    if (error) {
      *error = {"ProposalOptions", "scale", std::to_string(scale), "must be finite and > 0"};
    }
    return false;
  }
  // The ancestor kernel proposes the reals itself, around each ancestor (the normal kernel's
  // scale): another continuous kernel would be ignored.
  if (binary == BinaryKernelKind::kAncestor && continuous != ContinuousKernelKind::kNormal) {
    if (error) {
      *error = {"ProposalOptions",
                "continuous",
                ToString(continuous),
                "the ancestor kernel proposes the reals itself (continuous = normal)"};
    }
    return false;
  }
  return true;
}

bool ProposalOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

ProposalOptions ResolvedProposal(ProposalOptions options, bool mixed) {
  if (options.binary == BinaryKernelKind::kAuto) {
    options.binary = mixed && options.continuous == ContinuousKernelKind::kNormal
                         ? BinaryKernelKind::kAncestor
                         : BinaryKernelKind::kIndependent;
  }
  return options;
}

std::unique_ptr<BinaryKernel> MakeBinaryKernel(const ProposalOptions& options) {
  switch (options.binary) {
    case BinaryKernelKind::kIndependent:
      return MakeIndependentKernel();
    case BinaryKernelKind::kLogistic:
      return MakeLogisticKernel(options.logistic);
    case BinaryKernelKind::kAncestor:
    case BinaryKernelKind::kAuto:
      break;  // joint, or not resolved: MakeJointKernel
  }
  throw Error(ErrorKind::kConfig,
              "ProposalOptions::binary = " + std::to_string(static_cast<int>(options.binary)) +
                  "; not a known binary kernel");
}

std::unique_ptr<JointKernel> MakeJointKernel(const ProposalOptions& given,
                                             const ParameterSpace& space) {
  const ProposalOptions options = ResolvedProposal(
      given, AnyUncertainBit(space.binary().free_prior_one()) && space.num_reals() > 0);
  std::string why;
  if (!options.IsValid(&why)) throw Error(ErrorKind::kConfig, why);
  if (options.binary == BinaryKernelKind::kAncestor) return MakeAncestorKernel(options.scale);
  return MakeProductKernel(MakeBinaryKernel(options), MakeContinuousKernel(options));
}

}  // namespace combabc
