#pragma once
// Which kernels propose a wave, and their options ([proposal] in the config; docs/config.md).
#include <memory>
#include <string>

#include "combabc/core/enum_names.hpp"
#include "combabc/core/validation_error.hpp"
#include "combabc/proposals/proposal.hpp"

namespace combabc {

enum class BinaryKernelKind {
  // The default: kAncestor for a mixed space (free bits and reals, continuous = kNormal), where
  // the product kernels can lose minor modes whose bit patterns need their own reals
  // (docs/algorithm.md, "Joint: `ancestor`"); kIndependent otherwise. Resolved against the space
  // (ResolvedProposal) before a run records its options.
  kAuto,
  kIndependent,  // Eq. 2 / Eq. 3: each free bit on its own
  kLogistic,     // logistic conditionals (Schaefer & Chopin 2013): p(x) = prod p(x_i | x_<i)
  // Not a binary kernel: the joint ancestor kernel (ancestor_kernel.hpp), which proposes the bits
  // and the reals together (the reals with ProposalOptions::scale; continuous must be kNormal).
  kAncestor,
};
template <>
struct EnumNames<BinaryKernelKind> {
  static constexpr std::pair<BinaryKernelKind, const char*> kNames[] = {
      {BinaryKernelKind::kAuto, "auto"},
      {BinaryKernelKind::kIndependent, "independent"},
      {BinaryKernelKind::kLogistic, "logistic"},
      {BinaryKernelKind::kAncestor, "ancestor"},
  };
};

enum class ContinuousKernelKind {
  kNormal,  // multivariate normal, covariance = scale x the weighted covariance (Beaumont 2009)
  kOlcm,    // optimal local covariance matrix per particle (Filippi et al. 2013)
};
template <>
struct EnumNames<ContinuousKernelKind> {
  static constexpr std::pair<ContinuousKernelKind, const char*> kNames[] = {
      {ContinuousKernelKind::kNormal, "normal"},
      {ContinuousKernelKind::kOlcm, "olcm"},
  };
};

struct LogisticKernelOptions {
  // A predecessor x_k enters bit i's regression when |weighted correlation(x_i, x_k)| exceeds
  // this (Schaefer & Chopin's sparse selection).
  double min_correlation = 0.075;
  // At most this many predecessors per bit (the most correlated ones).
  int max_predecessors = 8;
  // Ridge penalty on the regression coefficients (not the intercept), scaled by the population's
  // total weight 1: keeps separable fits finite.
  double ridge = 1e-3;
  // A bit whose weighted marginal is within this of 0 or 1 is proposed from its marginal alone
  // (near-constant bits carry no usable regression).
  double min_marginal = 0.02;
  // Conditional probabilities are clipped to [clip, 1 - clip] so no configuration has q = 0.
  double clip = 1e-4;

  // On failure `error` names the field (owner "LogisticKernelOptions").
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "LogisticKernelOptions::field = value; constraint".
  bool IsValid(std::string* why) const;
};

struct ProposalOptions {
  BinaryKernelKind binary = BinaryKernelKind::kAuto;
  LogisticKernelOptions logistic;
  ContinuousKernelKind continuous = ContinuousKernelKind::kNormal;
  // kNormal and kAncestor: covariance = scale x weighted covariance (2 is Beaumont et al.'s
  // choice).
  double scale = 2.0;

  // On failure `error` names the field (owner "ProposalOptions"): "scale", "logistic.clip".
  bool IsValid(ValidationError* error) const;
  // The same as one sentence: "ProposalOptions::field = value; constraint".
  bool IsValid(std::string* why) const;
};

// The options with kAuto resolved for a space with (`mixed`) or without both free bits and reals.
ProposalOptions ResolvedProposal(ProposalOptions options, bool mixed);

// The parts of a product kernel: MakeBinaryKernel throws Error(kConfig) for kAncestor and kAuto.
std::unique_ptr<BinaryKernel> MakeBinaryKernel(const ProposalOptions& options);
std::unique_ptr<ContinuousKernel> MakeContinuousKernel(const ProposalOptions& options);
// The kernel a run proposes from: MakeAncestorKernel(scale) for kAncestor, else MakeProductKernel
// of the two above; kAuto as ResolvedProposal resolves it for `space`. Throws Error(kConfig) with
// IsValid's message for invalid options.
std::unique_ptr<JointKernel> MakeJointKernel(const ProposalOptions& options,
                                             const ParameterSpace& space);

}  // namespace combabc
