#include "combabc/samplers/smc_options.hpp"

#include <cmath>

namespace combabc {

bool MoveOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool MoveOptions::IsValid(ValidationError* error) const {
  auto fail = [&](const std::string& field, double value, const std::string& constraint) {
    if (error) *error = {"MoveOptions", field, std::to_string(value), constraint};
    return false;
  };
  if (!(ess_fraction > 0.0 && ess_fraction < 1.0)) {
    return fail("ess_fraction", ess_fraction, "must be in (0, 1)");
  }
  if (!(stay_probability > 0.0 && stay_probability < 1.0)) {
    return fail("stay_probability", stay_probability, "must be in (0, 1)");
  }
  if (max_rounds < 1 || max_rounds > 10'000) {
    if (error) {
      *error = {"MoveOptions", "max_rounds", std::to_string(max_rounds), "must be in [1, 10000]"};
    }
    return false;
  }
  if (!(independent_share >= 0.0 && independent_share <= 1.0)) {
    return fail("independent_share", independent_share, "must be in [0, 1]");
  }
  if (!(min_survivor_fraction > 0.0 && min_survivor_fraction < 1.0)) {
    return fail("min_survivor_fraction", min_survivor_fraction, "must be in (0, 1)");
  }
  return true;
}

bool SmcOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool SmcOptions::IsValid(ValidationError* error) const {
  // fail(field, value, constraint); with no value, constraint is what follows the field.
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rest) {
    if (error) *error = {"SmcOptions", field, value, rest};
    return false;
  };
  // A member's own check, its field put below the member's name.
  auto below = [&](const std::string& member) {
    if (error) {
      error->owner = "SmcOptions";
      error->field = member + "." + error->field;
    }
    return false;
  };
  auto text = [](auto v) { return std::to_string(v); };
  if (num_waves < 1) return fail("num_waves", text(num_waves), "must be >= 1");
  if (accepted_per_wave < 1) {
    return fail("accepted_per_wave", text(accepted_per_wave), "must be >= 1");
  }
  if (!accepted_by_wave.empty() && static_cast<int>(accepted_by_wave.size()) != num_waves) {
    return fail("accepted_by_wave",
                "",
                "has " + text(accepted_by_wave.size()) +
                    " entries; must have one per wave (num_waves = " + text(num_waves) + ")");
  }
  for (std::size_t t = 0; t < accepted_by_wave.size(); ++t) {
    if (accepted_by_wave[t] < 1) {
      return fail("accepted_by_wave[" + text(t) + "]", text(accepted_by_wave[t]), "must be >= 1");
    }
  }
  for (std::size_t k = 0; k < thresholds.size(); ++k) {
    if (!thresholds[k].IsValid(num_waves, error)) return below("thresholds[" + text(k) + "]");
  }
  if (!tempering.IsValid(error)) return below("tempering");
  if (!proposal.IsValid(error)) return below("proposal");
  if (tempering.kind == TemperingKind::kList &&
      static_cast<int>(tempering.values.size()) < num_waves - 1) {
    return fail("tempering.values",
                "",
                "has " + text(tempering.values.size()) + " entries; must have " +
                    text(num_waves - 1) + " (one per wave after the first)");
  }
  if (threads < 0 || threads > 4096) {
    return fail("threads", text(threads), "must be in [0, 4096] (0 = all cores)");
  }
  if (max_simulations < 0) return fail("max_simulations", text(max_simulations), "must be >= 0");
  if (!(min_acceptance_rate >= 0.0 && min_acceptance_rate <= 1.0)) {
    return fail("min_acceptance_rate", text(min_acceptance_rate), "must be in [0, 1]");
  }
  if (acceptance_floor_after < 1) {
    return fail("acceptance_floor_after", text(acceptance_floor_after), "must be >= 1");
  }
  if (!(max_failure_fraction >= 0.0 && max_failure_fraction <= 1.0)) {
    return fail("max_failure_fraction",
                text(max_failure_fraction),
                "must be in [0, 1] (1 = never stop for failures)");
  }
  if (failure_fraction_after < 1) {
    return fail("failure_fraction_after", text(failure_fraction_after), "must be >= 1");
  }
  if (!(max_wall_time_s >= 0.0 && std::isfinite(max_wall_time_s))) {
    return fail("max_wall_time_s", text(max_wall_time_s), "must be finite and >= 0");
  }
  if (batch_size < 0) return fail("batch_size", text(batch_size), "must be >= 0 (0 = automatic)");
  if (method == SamplerMethod::kResampleMove && estimator == Estimator::kPaper) {
    return fail("method",
                "resample_move",
                "it needs estimator = importance (the paper estimator's equal weights are not "
                "draws from a wave's target)");
  }
  if (!moves.IsValid(error)) return below("moves");
  if (!multi_fidelity.IsValid(error)) return below("multi_fidelity");
  return true;
}

}  // namespace combabc
