#include "combabc/samplers/multi_fidelity.hpp"

#include <cmath>

namespace combabc {

bool MultiFidelityOptions::IsValid(std::string* why) const {
  auto probability = [&](const char* name, double eta) {
    if (eta > 0.0 && eta <= 1.0) return true;
    if (why) {
      *why = std::string("MultiFidelityOptions::") + name + " = " + std::to_string(eta) +
             "; must be in (0, 1]";
    }
    return false;
  };
  if (!probability("continue_if_accepted", continue_if_accepted) ||
      !probability("continue_if_rejected", continue_if_rejected) || !probability("floor", floor)) {
    return false;
  }
  if (cost_ratio >= 0.0 && std::isfinite(cost_ratio)) return true;
  if (why) {
    *why = "MultiFidelityOptions::cost_ratio = " + std::to_string(cost_ratio) +
           "; must be > 0, or 0 to measure it";
  }
  return false;
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
