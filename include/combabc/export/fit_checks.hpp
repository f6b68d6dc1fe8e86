#pragma once
// Fit and sanity checks of a run (docs/history.md, "Checks"): pure functions of its history (the
// measured data, the stored curves, the thresholds), so that run and resume print them, export
// writes them into summary.json and tests call them without the CLI. Each warning is one line
// naming the likely cause and the config key; none stops a run.
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "combabc/core/validation_error.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/metrics/metric_component.hpp"

namespace combabc {

// A noise-aware (gaussian, folded_normal) distance component's error model as the run's config
// states it, which
// the history does not record: the services layer reads it from the config (as it does
// ExportOptions::bit_positions). Its sigma is sqrt(sigma_noise^2 + sigma_model^2), in the units
// the metric compares (the normalised profile when the data are normalised).
struct StatedNoise {
  std::size_t component = 0;          // index into RunMetadata::distance_components
  std::optional<double> sigma_noise;  // none: "estimate", the data's own (EstimateNoiseSigma)
  double sigma_model = 0.0;
  // The component's window, metres: the measured points it compares.
  double from = -std::numeric_limits<double>::infinity();
  double to = std::numeric_limits<double>::infinity();
  // folded_normal: the data are amplitudes, and the estimate is EstimateAmplitudeNoise's.
  NoiseModel model = NoiseModel::kGaussian;
};

// The documented levels of the checks (docs/history.md, "Checks").
struct FitCheckOptions {
  // units_mismatch: the data's peak lies outside the 5-95 % range of the first wave's curves'
  // peaks at the measured positions by more than this factor (1.5 orders of magnitude).
  double scale_factor = 31.6;
  // negative_data: a measured value below -max(4 noise sigmas, this fraction of the data's peak)
  // (noise on an amplitude near zero makes small negative values).
  double negative_fraction = 0.05;
  // poor_fit: the best accepted curve's RMS residual exceeds this many noise sigmas, or noise of
  // that sigma leaves residuals as large with a probability below poor_fit_p (chi-square against
  // a stated sigma, F against the data's estimate; FitVerdict). Between poor_fit_p and
  // doubtful_fit_p the verdict is "doubtful": not poor enough to warn, not "good".
  double poor_fit_ratio = 3.0;
  double poor_fit_p = 1e-3;
  double doubtful_fit_p = 0.05;
  // noise_below_estimate: a noise-aware component's stated sigma is below this fraction of the
  // noise estimated from its experiment's data.
  double noise_below_fraction = 0.5;
  // threshold_stalled: the last `stall_waves` complete waves cut a plain threshold by less than
  // this fraction in all.
  double stall_reduction = 0.1;
  int stall_waves = 2;
  // threshold_below_noise (plain thresholds only): the final wave's accepted curves lie within
  // `overfit_loglik` units of Gaussian log-likelihood of the best of them (n (worst RMS^2 -
  // best RMS^2) / (2 sigma^2) below it), and earlier waves hold particles within as much of the
  // best that the final wave no longer accepts: the threshold rejects what the noise cannot tell
  // apart.
  double overfit_loglik = 1.0;
  // noise_unresolved: the best curve, noise-free, reads more than this fraction of the data's
  // noise estimate (the profile's own detail, not noise): threshold_below_noise is not checked.
  double shape_fraction = 0.5;
  // The predictive band: these quantiles of the final wave's accepted curves.
  double band_low = 0.05;
  double band_high = 0.95;
  // Not a level: the run's noise-aware components as its config states them (none for a run
  // without a config, or without such components).
  std::vector<StatedNoise> stated_noise;
  // Fills `error` (may be null) with the first field that fails, without an owner or a value
  // ("band_low" "< band_high must lie in [0, 1]").
  bool IsValid(ValidationError* error) const;
  // The same check as a sentence: "scale_factor must be > 1", "stated_noise[0].from must be <= to".
  bool IsValid(std::string* why) const;
};

struct CheckMessage {
  std::string severity;  // "warning" or "note"
  std::string code;      // e.g. "units_mismatch"
  std::string message;   // one line: what, the likely cause, the config key
};

// Before sampling: the data against the first wave's curves (the prior predictive when its
// thresholds were infinite, as by default).
struct ExperimentOverview {
  std::string experiment;
  std::size_t points = 0;  // measured points
  double position_low = 0.0;
  double position_high = 0.0;
  double data_low = 0.0;   // smallest measured value
  double data_peak = 0.0;  // largest |measured value|
  // 5 % and 95 % quantiles of the first wave's curves' peaks |Y*| at the measured positions (as
  // the distance compares them: scaled to peak 1 when the data are normalised); NaN without curves.
  double simulated_peak_low = 0.0;
  double simulated_peak_high = 0.0;
  bool prior_predictive = false;  // the first wave accepted every draw (infinite thresholds)
  bool normalised = false;        // the data's peak is exactly 1 ([data] normalise)
};

struct NoiseLevel {
  std::string experiment;
  // EstimateNoiseSigma of the measured points, or EstimateAmplitudeNoise for an experiment with a
  // folded_normal component.
  double value = 0.0;
  std::string method;
  double dof = 0.0;  // the estimate's effective degrees of freedom (FitVerdict::sigma_dof)
  // The same estimate of the best accepted curve (noise-free): what the profile itself reads;
  // NaN without curves.
  double shape = 0.0;
};

// The best accepted curve (the smallest RMS residual over the experiment's measured points)
// against the noise. An experiment with noise-aware components is judged against their stated
// sigmas over their windows' points ("stated"); else, or when a component's sigma_noise is
// "estimate", against the data's estimate ("estimated"), over every measured point.
struct FitVerdict {
  std::string experiment;
  double best_rms = 0.0;     // the best curve's RMS residual over the `points` judged
  double noise_sigma = 0.0;  // NoiseLevel::value, the data's estimate
  double sigma = 0.0;        // the sigma judged against (several components: best_rms / ratio)
  std::string sigma_source;  // "stated" or "estimated"
  std::size_t points = 0;
  double ratio = 0.0;  // best_rms / sigma (several components: sqrt(chi2 / points))
  double chi2 = 0.0;   // the sum of squared residuals in units of sigma^2, points * ratio^2
  // The estimate's effective degrees of freedom ((N - 5) / 2.91 for N points: the fifth
  // differences overlap; the amplitude estimate's: its floor points plus its differences / 2.91);
  // infinite for a stated sigma, taken as known.
  double sigma_dof = 0.0;
  // P(residuals as large | the model at its best, noise of that sigma): chi-square with `points`
  // degrees of freedom against a stated sigma, F(points, sigma_dof) of ratio^2 against an
  // estimated one (its own scatter counts).
  double p_value = 0.0;
  // "poor" when ratio > FitCheckOptions::poor_fit_ratio or p_value < poor_fit_p, "doubtful" when
  // p_value < doubtful_fit_p, else "good".
  std::string verdict;
};

// The posterior predictive check of one experiment: the final complete wave's accepted curves at
// the measured positions (in range of the outputs), weighted as the run's estimator weighs them.
struct PredictiveCheck {
  std::string experiment;
  int wave = 0;  // 1-based
  std::vector<double> positions;
  std::vector<double> measured;
  std::vector<double> band_low;
  std::vector<double> band_high;
  std::vector<double> median;
  std::vector<double> best;       // the accepted curve with the smallest RMS residual
  std::vector<double> residuals;  // measured - best
};

struct FitChecks {
  std::vector<ExperimentOverview> overview;
  std::vector<CheckMessage> before;
  std::vector<CheckMessage> after;
  std::vector<NoiseLevel> noise;
  std::vector<FitVerdict> fit;
  std::vector<PredictiveCheck> predictive;
};

// The checks before sampling alone (`overview` and `before`): the data against `first_wave`
// (null: none yet). Its curve-based warnings (units_mismatch, negative_data, zero_outputs) need
// the prior predictive, a first wave of infinite thresholds. Run and resume print them as soon as
// the first wave has ended, from the wave as stored, so they equal ComputeFitChecks' own.
FitChecks ComputeBeforeChecks(const RunMetadata& metadata,
                              const WaveRecord* first_wave,
                              const FitCheckOptions& options = {});

// Every check: ComputeBeforeChecks of the history's first wave, then those after sampling
// (`noise`, `fit`, `predictive`, `after`) from its final complete wave.
FitChecks ComputeFitChecks(const RunMetadata& metadata,
                           const RunHistory& history,
                           const FitCheckOptions& options = {});

// What the CLI prints on stderr, one line each. Before: per experiment its measured points, range
// and peak against the first wave's curves, then the before warnings. After: per experiment the
// noise and the best fit's verdict, then the after warnings and notes. FormatFitChecks: both.
std::string FormatBeforeChecks(const FitChecks& checks, const std::string& position_unit);
std::string FormatAfterChecks(const FitChecks& checks);
std::string FormatFitChecks(const FitChecks& checks, const std::string& position_unit);

// summary.json's "checks" object (docs/history.md), indented by `indent` spaces after its first
// line.
std::string FitChecksJson(const FitChecks& checks, int indent);

}  // namespace combabc
