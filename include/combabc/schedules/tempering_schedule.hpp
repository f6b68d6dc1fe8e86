#pragma once
// Tempering of the combinatorial proposal toward the prior (paper Eq. 3):
//   q(theta) ∝ q~(theta)^(1 - phi(t)) p(theta)^phi(t).
// For independent Bernoullis this is again an independent Bernoulli per bit (see
// TemperedProbability and docs/algorithm.md).
#include <optional>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"
#include "combabc/core/validation_error.hpp"

namespace combabc {

enum class TemperingKind {
  kNone,    // phi(t) = 0: Eq. 2 untempered
  kLinear,  // phi(1) = phi0 falling linearly to phi(T-1) = 0 over the planned waves
  kList,    // phi(t) = values[t - 1] for t >= 1
};
template <>
struct EnumNames<TemperingKind> {
  static constexpr std::pair<TemperingKind, const char*> kNames[] = {
      {TemperingKind::kNone, "none"},
      {TemperingKind::kLinear, "linear"},
      {TemperingKind::kList, "list"},
  };
};

enum class TemperingForm {
  kGeometric,  // Eq. 3 exactly: q ∝ q~^(1-phi) p^phi. A bit with p^ = 0 stays 0 unless phi = 1.
  kMixture,    // q = (1 - phi) q~ + phi p: an extension that does unstick p^ = 0 or 1 bits.
};
template <>
struct EnumNames<TemperingForm> {
  static constexpr std::pair<TemperingForm, const char*> kNames[] = {
      {TemperingForm::kGeometric, "geometric"},
      {TemperingForm::kMixture, "mixture"},
  };
};

struct TemperingSchedule {
  TemperingKind kind = TemperingKind::kNone;
  TemperingForm form = TemperingForm::kGeometric;
  double phi0 = 0.5;           // kLinear: phi at wave 1, in [0, 1]
  std::vector<double> values;  // kList: phi for waves 1, 2, ...; each in [0, 1]

  // On failure `error` names the field ("phi0", "values[1]"), with no owner.
  bool IsValid(ValidationError* error) const;
  // The same as one sentence that `where` prefixes, e.g. "SmcOptions::tempering".
  bool IsValid(const std::string& where, std::string* why) const;
  // phi(t) for the proposal of wave t >= 1 of `planned_waves`.
  double Phi(int wave, int planned_waves) const;
};

// Per-bit probability of 1 under the tempered proposal, given p^ = fraction of 1s (Eq. 2) and the
// prior's P(1) = prior. Geometric (Eq. 3), normalised over {0, 1}:
//   q = p^^(1-phi) prior^phi / (p^^(1-phi) prior^phi + (1-p^)^(1-phi) (1-prior)^phi)
// with 0^0 = 1, so p^ = 0 gives q = 0 for phi < 1 and q = prior at phi = 1 (likewise p^ = 1).
double TemperedProbability(double p_hat, double prior, double phi, TemperingForm form);

}  // namespace combabc
