#include "combabc/samplers/smc_options.hpp"

#include <cmath>

namespace combabc {

bool MoveOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = "MoveOptions::" + msg;
    return false;
  };
  if (!(ess_fraction > 0.0 && ess_fraction < 1.0)) {
    return fail("ess_fraction = " + std::to_string(ess_fraction) + "; must be in (0, 1)");
  }
  if (!(stay_probability > 0.0 && stay_probability < 1.0)) {
    return fail("stay_probability = " + std::to_string(stay_probability) + "; must be in (0, 1)");
  }
  if (max_rounds < 1 || max_rounds > 10'000) {
    return fail("max_rounds = " + std::to_string(max_rounds) + "; must be in [1, 10000]");
  }
  if (!(independent_share >= 0.0 && independent_share <= 1.0)) {
    return fail("independent_share = " + std::to_string(independent_share) + "; must be in [0, 1]");
  }
  if (!(min_survivor_fraction > 0.0 && min_survivor_fraction < 1.0)) {
    return fail("min_survivor_fraction = " + std::to_string(min_survivor_fraction) +
                "; must be in (0, 1)");
  }
  return true;
}

bool SmcOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = "SmcOptions::" + msg;
    return false;
  };
  if (num_waves < 1) return fail("num_waves = " + std::to_string(num_waves) + "; must be >= 1");
  if (accepted_per_wave < 1) {
    return fail("accepted_per_wave = " + std::to_string(accepted_per_wave) + "; must be >= 1");
  }
  if (!accepted_by_wave.empty() && static_cast<int>(accepted_by_wave.size()) != num_waves) {
    return fail("accepted_by_wave has " + std::to_string(accepted_by_wave.size()) +
                " entries; must have one per wave (num_waves = " + std::to_string(num_waves) + ")");
  }
  for (std::size_t t = 0; t < accepted_by_wave.size(); ++t) {
    if (accepted_by_wave[t] < 1) {
      return fail("accepted_by_wave[" + std::to_string(t) +
                  "] = " + std::to_string(accepted_by_wave[t]) + "; must be >= 1");
    }
  }
  for (std::size_t k = 0; k < thresholds.size(); ++k) {
    if (!thresholds[k].IsValid(
            "SmcOptions::thresholds[" + std::to_string(k) + "]", num_waves, why)) {
      return false;
    }
  }
  if (!tempering.IsValid("SmcOptions::tempering", why)) return false;
  if (!proposal.IsValid(why)) {
    if (why) *why = "SmcOptions::proposal." + why->substr(why->find("::") + 2);
    return false;
  }
  if (tempering.kind == TemperingKind::kList &&
      static_cast<int>(tempering.values.size()) < num_waves - 1) {
    return fail("tempering.values has " + std::to_string(tempering.values.size()) +
                " entries; must have " + std::to_string(num_waves - 1) +
                " (one per wave after the first)");
  }
  if (threads < 0 || threads > 4096) {
    return fail("threads = " + std::to_string(threads) + "; must be in [0, 4096] (0 = all cores)");
  }
  if (max_simulations < 0) {
    return fail("max_simulations = " + std::to_string(max_simulations) + "; must be >= 0");
  }
  if (!(min_acceptance_rate >= 0.0 && min_acceptance_rate <= 1.0)) {
    return fail("min_acceptance_rate = " + std::to_string(min_acceptance_rate) +
                "; must be in [0, 1]");
  }
  if (acceptance_floor_after < 1) {
    return fail("acceptance_floor_after = " + std::to_string(acceptance_floor_after) +
                "; must be >= 1");
  }
  if (!(max_failure_fraction >= 0.0 && max_failure_fraction <= 1.0)) {
    return fail("max_failure_fraction = " + std::to_string(max_failure_fraction) +
                "; must be in [0, 1] (1 = never stop for failures)");
  }
  if (failure_fraction_after < 1) {
    return fail("failure_fraction_after = " + std::to_string(failure_fraction_after) +
                "; must be >= 1");
  }
  if (!(max_wall_time_s >= 0.0 && std::isfinite(max_wall_time_s))) {
    return fail("max_wall_time_s = " + std::to_string(max_wall_time_s) +
                "; must be finite and >= 0");
  }
  if (batch_size < 0) {
    return fail("batch_size = " + std::to_string(batch_size) + "; must be >= 0 (0 = automatic)");
  }
  if (method == SamplerMethod::kResampleMove && estimator == Estimator::kPaper) {
    return fail(
        "method = resample_move; it needs estimator = importance (the paper estimator's equal "
        "weights are not draws from a wave's target)");
  }
  if (!moves.IsValid(why)) {
    if (why) *why = "SmcOptions::moves." + why->substr(why->find("::") + 2);
    return false;
  }
  if (!multi_fidelity.IsValid(why)) {
    if (why) *why = "SmcOptions::multi_fidelity." + why->substr(why->find("::") + 2);
    return false;
  }
  return true;
}

}  // namespace combabc
