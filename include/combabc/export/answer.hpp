#pragma once
// The answer of a run or an enumeration, in numbers: per bit P(bit = 1) with its Monte-Carlo
// standard error and a verdict, the most probable configurations with their posterior mass, and
// each wave's ESS (of the weights, of the bits and of each real) and simulations. One pure function
// of a loaded history computes it, for the terminal at the end of `combabc run` / `resume` /
// `enumerate` (AnswerText) and for summary.json's "answer" (AnswerJson), so that both show the same
// numbers (docs/history.md, "The answer").
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "combabc/core/enum_names.hpp"
#include "combabc/history/history_store.hpp"

namespace combabc {

// A bit's verdict at kVerdictLevel: fixed (bit = 1) if P >= level, free (bit = 0) if
// P <= 1 - level, else not determined. For simulators other than the sensor "fixed" reads
// "bit = 1" and "free" "bit = 0".
enum class Verdict { kFixed, kFree, kNotDetermined };
template <>
struct EnumNames<Verdict> {
  static constexpr std::pair<Verdict, const char*> kNames[] = {
      {Verdict::kFixed, "fixed"},
      {Verdict::kFree, "free"},
      {Verdict::kNotDetermined, "not determined"},
  };
};

// The verdicts' level. The verdict reads the estimate P alone: the level is a statement about the
// posterior probability, and the standard error printed beside P says how far the estimate may be
// off (a verdict made stricter by it would change with the run's size, not with the evidence).
inline constexpr double kVerdictLevel = 0.95;
Verdict VerdictOf(double p_one, double level = kVerdictLevel);

// Where a bit acts on the structure: for the built-in sensor a clamp's edge (1: y = 0, 2: y =
// width) and its span along x in metres. Other simulators' bits have none.
struct BitPosition {
  int edge = 0;
  double start_m = 0.0;
  double end_m = 0.0;
  // "edge 1, 0-5 cm".
  std::string Text() const;
};

struct AnswerBit {
  int number = 0;  // from 1
  std::string name;
  std::optional<BitPosition> position;
  double p_one = 0.0;  // P(bit = 1) under the estimator (the sensor: P(fixed))
  double mc_se = 0.0;  // its Monte-Carlo standard error (delta method); 0 when exact (enumerated)
  Verdict verdict = Verdict::kNotDetermined;
};

struct AnswerConfiguration {
  std::string bits;                // "0110...", bit 1 first
  double mass = 0.0;               // posterior mass
  std::optional<double> mass_se;   // none when exact
  std::vector<std::string> fixed;  // the names of its bits set to 1
};

// A continuous parameter's posterior mean and sd, each with its Monte-Carlo standard error (delta
// method), and the mean's effective sample size (samplers/monte_carlo_error.hpp).
struct AnswerReal {
  std::string name;
  double mean = 0.0;
  double mc_se = 0.0;
  double sd = 0.0;
  double sd_se = 0.0;
  double ess = 0.0;
  // The 5 %, 50 % and 95 % quantiles of its posterior: the answer wave's particles under their
  // weights, negative (multi-fidelity) ones as 0 (AnswerQuantile); NaN when no weight is positive.
  double q05 = 0.0;
  double median = 0.0;
  double q95 = 0.0;
};

struct WaveEffort {
  int wave = 0;      // from 1
  double ess = 0.0;  // the weights' ESS, 1 / sum w^2
  // The per-quantity ESS Var_w(f) / SE_f^2 (WaveMonteCarloErrors): the smallest over the bits
  // that vary among the wave's particles (none without such bits, and for an enumeration), and
  // each real's mean's.
  std::optional<double> bits_ess;
  std::vector<double> reals_ess;
  std::int64_t simulations = 0;
  bool complete = false;
};

inline constexpr std::size_t kAnswerConfigurations = 10;

// A noise-aware (likelihood) component's temperature in the answer's wave (docs/algorithm.md,
// "Noise-aware acceptance"): only T = 1 is the posterior under the error model.
struct AnswerTemperature {
  std::string component;  // the distance component's name
  double temperature = 1.0;
};

// A pattern class the mode-loss diagnostic flagged (WaveRecord::pattern_classes, docs/algorithm.md
// "Mode loss"): a pattern the previous wave held with `mass` that wave `wave` proposed with
// probability `proposal`.
struct ModeLossFlag {
  int wave = 0;      // from 1
  std::string bits;  // "0110...", bit 1 first
  double mass = 0.0;
  double proposal = 0.0;
};

struct Answer {
  int wave = 0;           // from 1, the wave the numbers are taken from; 0: no wave has particles
  int waves = 0;          // waves in the history, the incomplete last one included
  bool complete = false;  // false only when no wave is complete (then the last wave's numbers)
  bool exact = false;     // an enumeration: exact marginals and masses
  std::string estimator;  // "paper" or "importance": the run's, which the report shows too
  double verdict_level = kVerdictLevel;
  std::int64_t particles = 0;   // the wave's accepted particles (configurations when enumerated)
  std::int64_t distinct = 0;    // distinct configurations among them
  std::string termination;      // the run's (metadata), e.g. "budget_exhausted"
  std::vector<AnswerBit> bits;  // none in a continuous-only run
  std::vector<AnswerConfiguration> top_configurations;  // most probable first, at most 10; none
                                                        // without bits
  std::vector<AnswerReal> reals;                        // the run's [parameters.<name>]
  std::vector<WaveEffort> per_wave;
  // Multi-fidelity runs only (a wave with WaveRecord::multi_fidelity): the expensive simulations
  // of all waves, among `simulations` candidates, each of which ran the cheap simulator.
  std::optional<std::int64_t> expensive_simulations;
  std::int64_t simulations = 0;  // candidates of all waves
  // Every wave's flagged pattern classes, and one warning line per wave with any
  // (ModeLossWarning): the posterior may have lost a mode.
  std::vector<ModeLossFlag> mode_loss;
  std::vector<std::string> mode_loss_warnings;
  // The answer wave's temperature of each likelihood component, in component order (none in a
  // run without them). `tempered` when any is above 1: a run stopped early by a limit (or one
  // whose target temperature is above 1) answers with a tempered, flatter posterior, not the
  // posterior under the noise model.
  std::vector<AnswerTemperature> temperatures;
  bool tempered = false;
};

// The answer of a loaded history: the last complete wave (or, when no wave is complete, the last
// wave with particles), under the run's estimator. Standard errors: the delta method's for the
// self-normalised estimate under the particles' stored weights (WaveMonteCarloErrors; for the
// paper estimator's equal weights the textbook sqrt(p (1 - p) / n) and sd / sqrt(n)), which sees
// how the weights go with each quantity; an enumeration's numbers are exact (SE 0, mass_se none).
// `positions`: one per bit, or empty.
Answer SummariseAnswer(const RunMetadata& metadata,
                       const RunHistory& history,
                       const std::vector<std::optional<BitPosition>>& positions = {});

// The weighted `alpha`-quantile (the inverse of the weighted empirical CDF, no interpolation: the
// smallest value whose values at or below it carry at least a fraction alpha of the weight, ties
// by position) with negative weights counted as 0; NaN when no weight is positive. The answer's
// quantiles of a continuous parameter.
double AnswerQuantile(const std::vector<double>& values,
                      const std::vector<double>& weights,
                      double alpha);

// The answer as summary.json's "answer" object (docs/history.md), indented by `indent` spaces
// after its first line; "reals" only for a run with continuous parameters.
std::string AnswerJson(const Answer& answer, int indent = 2);

// The answer for a terminal: one screen (the sensor's clamps as one table per edge, side by side),
// then the `configurations` most probable configurations, the continuous parameters' means and sds,
// each wave's ESS and simulations, for a multi-fidelity run one line with its expensive
// simulations, and a "warning: " line per wave whose proposal may have lost a mode. A
// continuous-only run has no bit lines and no configurations.
std::string AnswerText(const Answer& answer, std::size_t configurations = 5);

}  // namespace combabc
