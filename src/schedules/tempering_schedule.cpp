#include "combabc/schedules/tempering_schedule.hpp"

#include <cmath>

namespace combabc {

bool TemperingSchedule::IsValid(const std::string& where, std::string* why) const {
  ValidationError error;
  const bool valid = IsValid(&error);
  error.field = where + "." + error.field;
  return ExplainValidation(valid, error, why);
}

bool TemperingSchedule::IsValid(ValidationError* error) const {
  auto fail = [&](const std::string& field, double value) {
    if (error) *error = {"", field, std::to_string(value), "must be in [0, 1]"};
    return false;
  };
  if (!(phi0 >= 0.0 && phi0 <= 1.0)) return fail("phi0", phi0);
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!(values[i] >= 0.0 && values[i] <= 1.0)) {
      return fail("values[" + std::to_string(i) + "]", values[i]);
    }
  }
  return true;
}

double TemperingSchedule::Phi(int wave, int planned_waves) const {
  if (wave <= 0) return 1.0;  // wave 0 proposes from the prior itself
  switch (kind) {
    case TemperingKind::kNone:
      return 0.0;
    case TemperingKind::kLinear:
      // Waves 1..T-1 propose; phi falls from phi0 at wave 1 to 0 at wave T-1.
      if (planned_waves <= 2) return phi0;
      return phi0 * static_cast<double>(planned_waves - 1 - wave) /
             static_cast<double>(planned_waves - 2);
    case TemperingKind::kList:
      return static_cast<std::size_t>(wave - 1) < values.size() ? values[wave - 1] : 0.0;
  }
  return 0.0;
}

double TemperedProbability(double p_hat, double prior, double phi, TemperingForm form) {
  if (form == TemperingForm::kMixture) return (1.0 - phi) * p_hat + phi * prior;
  // Eq. 3 per bit. std::pow(0, 0) = 1, which is the limit convention we document: an exact 0
  // stays 0 for phi < 1 (the geometric mean of 0 and anything is 0), and phi = 1 is the prior.
  const double one = std::pow(p_hat, 1.0 - phi) * std::pow(prior, phi);
  const double zero = std::pow(1.0 - p_hat, 1.0 - phi) * std::pow(1.0 - prior, phi);
  // Disjoint supports (p^ = 0 with prior = 1, or the reverse) cannot arise from accepted samples,
  // whose support lies inside the prior's; fall back to the prior rather than divide by zero.
  if (one + zero <= 0.0) return prior;
  return one / (one + zero);
}

}  // namespace combabc
