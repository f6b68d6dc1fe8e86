#include "combabc/samplers/multi_fidelity.hpp"

#include <cmath>
#include <utility>

namespace combabc {

bool MultiFidelityOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool MultiFidelityOptions::IsValid(ValidationError* error) const {
  auto fail = [&](const char* field, double value, const char* constraint) {
    if (error) *error = {"MultiFidelityOptions", field, std::to_string(value), constraint};
    return false;
  };
  for (const auto& [name, eta] : {std::pair{"continue_if_accepted", continue_if_accepted},
                                  std::pair{"continue_if_rejected", continue_if_rejected},
                                  std::pair{"floor", floor}}) {
    if (!(eta > 0.0 && eta <= 1.0)) return fail(name, eta, "must be in (0, 1]");
  }
  if (cost_ratio >= 0.0 && std::isfinite(cost_ratio)) return true;
  return fail("cost_ratio", cost_ratio, "must be > 0, or 0 to measure it");
}

double MultiFidelityMultiplier(const MultiFidelityOptions& options,
                               bool cheap_accepted,
                               bool continued,
                               bool expensive_accepted) {
  const double cheap = cheap_accepted ? 1.0 : 0.0;
  if (!continued) return cheap;
  const double eta = cheap_accepted ? options.continue_if_accepted : options.continue_if_rejected;
  return cheap + ((expensive_accepted ? 1.0 : 0.0) - cheap) / eta;
}

}  // namespace combabc
