// Fit and sanity checks of a run from its history (docs/history.md, "Checks").
#include "combabc/export/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <set>
#include <sstream>
#include <utility>

#include "combabc/core/check.hpp"
#include "combabc/export/export.hpp"
#include "combabc/export/tail_probability.hpp"
#include "combabc/metrics/composite_distance.hpp"
#include "export/json_text.hpp"

namespace combabc {
namespace {

using export_text::JsonArray;
using export_text::JsonNumber;
using export_text::JsonString;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Slack (metres) when placing a measured point among the output positions, as the distance's.
constexpr double kPositionSlack = 1e-9;
const char* const kNoiseMethod =
    "fifth divided differences of the measured points: MAD, then the RMS within 3 MADs "
    "(EstimateNoiseSigma)";
const char* const kAmplitudeNoiseMethod =
    "amplitudes folded at zero: the mean square of the points at the noise floor pooled with the "
    "clipped fifth divided differences of the rest (EstimateAmplitudeNoise)";

std::string Short(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

// "experiment \"45 cm\": " for a named experiment, "" for the single unnamed one.
std::string Prefix(const std::string& name) {
  return name.empty() ? std::string() : "experiment \"" + name + "\": ";
}

// One experiment's measured points that lie within its output positions, and where each is read
// from the simulated outputs (linear interpolation, as the distance reads them).
struct ExperimentView {
  ExperimentSlice slice;
  std::vector<double> x;
  std::vector<double> y;
  std::vector<std::size_t> index;  // absolute output index of the left neighbour
  std::vector<double> weight;      // of the right neighbour
  // The data are normalised (DataConfig::normalise makes max |y| exactly 1): the distance divides
  // each curve by its largest |Y*| at the measured positions, and so do the checks.
  bool normalised = false;
};

ExperimentView ViewOf(const RunMetadata& m, const ExperimentSlice& slice) {
  ExperimentView v;
  v.slice = slice;
  const auto out_begin =
      m.output_positions.begin() + static_cast<std::ptrdiff_t>(slice.first_output);
  const auto out_end = out_begin + static_cast<std::ptrdiff_t>(slice.outputs);
  double peak = 0.0;
  for (std::size_t i = 0; i < slice.measured; ++i) {
    peak = std::max(peak, std::abs(m.measured.values[slice.first_measured + i]));
  }
  v.normalised = peak == 1.0;
  if (slice.outputs == 0) return v;
  const double lo = *out_begin;
  const double hi = *(out_end - 1);
  for (std::size_t i = 0; i < slice.measured; ++i) {
    const double x = m.measured.positions[slice.first_measured + i];
    if (x < lo - kPositionSlack || x > hi + kPositionSlack) continue;
    v.x.push_back(x);
    v.y.push_back(m.measured.values[slice.first_measured + i]);
    if (slice.outputs == 1) {
      v.index.push_back(slice.first_output);
      v.weight.push_back(0.0);
      continue;
    }
    const auto upper = std::upper_bound(out_begin, out_end, x);
    std::size_t left = static_cast<std::size_t>(upper - out_begin);
    left = std::min(left == 0 ? 0 : left - 1, slice.outputs - 2);
    const double x0 = *(out_begin + static_cast<std::ptrdiff_t>(left));
    const double x1 = *(out_begin + static_cast<std::ptrdiff_t>(left + 1));
    v.index.push_back(slice.first_output + left);
    v.weight.push_back(std::clamp((x - x0) / (x1 - x0), 0.0, 1.0));
  }
  return v;
}

// A particle's curve at the view's measured points, scaled as the distance scales it; empty when
// the particle holds no output. `raw`: unscaled.
std::vector<double> CurveAt(const ExperimentView& v, const Particle& p, bool raw = false) {
  std::vector<double> out;
  if (p.output.empty() || v.x.empty()) return out;
  out.reserve(v.x.size());
  double peak = 0.0;
  for (std::size_t j = 0; j < v.x.size(); ++j) {
    const std::size_t i = v.index[j];
    const double w = v.weight[j];
    const double y0 = i < p.output.size() ? p.output[i] : kNaN;
    const double y1 = w > 0.0 && i + 1 < p.output.size() ? p.output[i + 1] : y0;
    out.push_back((1.0 - w) * y0 + w * y1);
    peak = std::max(peak, std::abs(out.back()));
  }
  if (v.normalised && !raw && peak > 0.0) {
    for (double& y : out) y /= peak;
  }
  return out;
}

double Rms(const std::vector<double>& curve, const std::vector<double>& y) {
  double sum = 0.0;
  for (std::size_t j = 0; j < y.size(); ++j) sum += (y[j] - curve[j]) * (y[j] - curve[j]);
  return std::sqrt(sum / static_cast<double>(y.size()));
}

// The q-quantile of values under weights (the first value whose cumulative weight reaches q of
// the total; equal weights when they sum to zero).
double WeightedQuantile(std::vector<std::pair<double, double>> values, double q) {
  std::sort(values.begin(), values.end());
  double total = 0.0;
  for (const auto& [value, weight] : values) total += weight;
  const bool equal = !(total > 0.0);
  if (equal) total = static_cast<double>(values.size());
  double sum = 0.0;
  for (const auto& [value, weight] : values) {
    sum += equal ? 1.0 : weight;
    if (sum >= q * total) return value;
  }
  return values.empty() ? kNaN : values.back().first;
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double at = q * static_cast<double>(values.size() - 1);
  const auto i = static_cast<std::size_t>(at);
  if (i + 1 >= values.size()) return values.back();
  return values[i] + (at - static_cast<double>(i)) * (values[i + 1] - values[i]);
}

const WaveRecord* FinalWave(const RunHistory& h) {
  for (auto it = h.waves.rbegin(); it != h.waves.rend(); ++it) {
    if (it->complete) return &*it;
  }
  return h.waves.empty() || h.waves.back().particles.empty() ? nullptr : &h.waves.back();
}

void Warn(std::vector<CheckMessage>& to, const char* code, const std::string& message) {
  to.push_back({"warning", code, message});
}

void Note(std::vector<CheckMessage>& to, const char* code, const std::string& message) {
  to.push_back({"note", code, message});
}

// The noise-aware components of an experiment, as stated (FitCheckOptions::stated_noise).
std::vector<const StatedNoise*> StatedOf(const ExperimentSlice& slice,
                                         const FitCheckOptions& options) {
  std::vector<const StatedNoise*> out;
  for (const StatedNoise& s : options.stated_noise) {
    if (s.component >= slice.first_component &&
        s.component < slice.first_component + slice.components) {
      out.push_back(&s);
    }
  }
  return out;
}

// The data's noise as the experiment's likelihood reads it: EstimateAmplitudeNoise where a
// component models amplitudes (folded_normal; its data are >= 0, or the distance refuses them),
// else EstimateNoiseSigma. NaN with fewer than 3 points.
NoiseLevel NoiseOf(const ExperimentView& v, const FitCheckOptions& options) {
  NoiseLevel noise{v.slice.name, kNaN, kNoiseMethod, kNaN, kNaN};
  if (v.y.size() < 3) return noise;
  const std::vector<const StatedNoise*> stated = StatedOf(v.slice, options);
  const bool folded =
      std::any_of(stated.begin(),
                  stated.end(),
                  [](const StatedNoise* s) { return s->model == NoiseModel::kFoldedNormal; }) &&
      std::all_of(v.y.begin(), v.y.end(), [](double y) { return y >= 0.0; });
  if (folded) {
    const AmplitudeNoiseEstimate estimate = EstimateAmplitudeNoise(v.x, v.y);
    noise.value = estimate.sigma;
    noise.dof = estimate.dof;
    noise.method = kAmplitudeNoiseMethod;
  } else {
    noise.value = EstimateNoiseSigma(v.x, v.y);
    noise.dof = std::max(1.0, (static_cast<double>(v.y.size()) - 5.0) / kFifthDifferenceOverlap);
  }
  return noise;
}

// The sigma a component's likelihood uses: its stated sigma_noise, or the data's estimate, with
// sigma_model in quadrature (as CompositeDistance compiles it).
double SigmaOf(const StatedNoise& s, double estimate) {
  return std::hypot(s.sigma_noise.value_or(estimate), s.sigma_model);
}

// noise_below_estimate: a stated sigma well below the data's own noise makes the likelihood too
// sharp: the posterior concentrates on whichever configuration best fits the noise (issue 35:
// 0.0007 against an estimate of 0.0073 held five clamps confidently wrong). Only a stated
// sigma_noise: "estimate" is the estimate. The Gaussian estimate reads low on amplitudes folded
// at zero (docs/algorithm.md, "Noise estimate": 0.0073 for the 45 cm example's true 0.010; the
// amplitude estimate of a folded_normal experiment 0.0105), so a stated sigma below half of it is
// below half the truth or more.
void NoiseBelowEstimate(const RunMetadata& m,
                        const ExperimentView& v,
                        double estimate,
                        const FitCheckOptions& options,
                        FitChecks& checks) {
  if (!(estimate > 0.0)) return;
  for (const StatedNoise* s : StatedOf(v.slice, options)) {
    if (!s->sigma_noise) continue;
    const double sigma = SigmaOf(*s, estimate);
    if (sigma >= options.noise_below_fraction * estimate) continue;
    const std::string name = s->component < m.distance_components.size()
                                 ? "\"" + m.distance_components[s->component].name + "\" "
                                 : "";
    Warn(checks.before,
         "noise_below_estimate",
         Prefix(v.slice.name) + "the sigma of the noise-aware component " + name +
             "(sqrt(sigma_noise^2 + sigma_model^2) = " + Short(sigma) + ") is " +
             Short(sigma / estimate) + " times the noise estimated from the data (" +
             Short(estimate) +
             "): the likelihood is too sharp, and the posterior too narrow, likely confidently "
             "wrong; give "
             "[metric] sigma_noise near the data's noise (or \"estimate\") and sigma_model for "
             "the model's discrepancy");
  }
}

// Before sampling: the data against the first wave's curves.
void CheckBefore(const RunMetadata& m,
                 const ExperimentView& v,
                 const WaveRecord* first,
                 const FitCheckOptions& options,
                 FitChecks& checks) {
  ExperimentOverview o;
  o.experiment = v.slice.name;
  o.points = v.slice.measured;
  o.normalised = v.normalised;
  o.simulated_peak_low = kNaN;
  o.simulated_peak_high = kNaN;
  const std::string prefix = Prefix(v.slice.name);
  // Negative beyond what noise on an amplitude near zero gives: 4 sigma and 5 % of the peak.
  const double estimate = NoiseOf(v, options).value;
  const double noise = std::isnan(estimate) ? 0.0 : estimate;
  double below = 0.0;
  for (double y : v.y) below = std::max(below, std::abs(y));
  below = -std::max(4.0 * noise, options.negative_fraction * below);
  std::size_t negative = 0;
  for (std::size_t i = 0; i < v.y.size(); ++i) {
    if (i == 0) {
      o.position_low = v.x[i];
      o.data_low = v.y[i];
    }
    o.position_high = v.x[i];
    o.data_low = std::min(o.data_low, v.y[i]);
    o.data_peak = std::max(o.data_peak, std::abs(v.y[i]));
    if (v.y[i] < below) ++negative;
  }
  std::vector<double> peaks;
  double lowest = std::numeric_limits<double>::infinity();
  if (first != nullptr) {
    o.prior_predictive = std::all_of(first->thresholds.begin(),
                                     first->thresholds.end(),
                                     [](double e) { return std::isinf(e) && e > 0; });
    for (const Particle& p : first->particles) {
      const std::vector<double> raw = CurveAt(v, p, /*raw=*/true);
      if (raw.empty()) continue;
      double peak = 0.0;
      for (double y : raw) {
        peak = std::max(peak, std::abs(y));
        lowest = std::min(lowest, y);
      }
      peaks.push_back(v.normalised && peak > 0.0 ? 1.0 : peak);
    }
  }
  if (!peaks.empty()) {
    o.simulated_peak_low = Quantile(peaks, 0.05);
    o.simulated_peak_high = Quantile(peaks, 0.95);
  }
  checks.overview.push_back(o);
  if (v.y.empty()) {
    Warn(checks.before,
         "no_data_in_range",
         prefix +
             "no measured point lies within the simulated positions: check [data] "
             "position_unit against the model's (m)");
    return;
  }
  // The run's, not an experiment's: said once, with the first experiment.
  if (first != nullptr && first->particles.empty() && first->candidates > 0 &&
      checks.overview.size() == 1) {
    Warn(checks.before,
         "nothing_accepted",
         "the first wave accepted none of its " + std::to_string(first->candidates) +
             " candidates: every distance was infinite or above the first threshold; a model "
             "whose outputs are all zero ([model.load] amplitude = 0?) cannot be compared");
  }
  NoiseBelowEstimate(m, v, noise, options, checks);
  // The scale and sign of the curves say something about the model only when nothing selected
  // them: a first wave with finite thresholds (an enumeration, a finite [metric] initial) holds
  // the curves nearest the data, not the prior predictive.
  if (!o.prior_predictive) return;
  if (!peaks.empty() && std::all_of(peaks.begin(), peaks.end(), [](double p) { return p == 0; })) {
    Warn(checks.before,
         "zero_outputs",
         prefix +
             "every simulated curve of the first wave is zero at the measured positions "
             "(every distance is infinite): the model is not loaded; check [model.load] "
             "amplitude");
    return;
  }
  if (negative > 0 && !peaks.empty() && lowest >= 0.0) {
    Warn(checks.before,
         "negative_data",
         prefix + std::to_string(negative) + " of " + std::to_string(v.y.size()) +
             " measured values are below " + Short(below) +
             ", beyond the noise, but the model's outputs are amplitudes (|w| >= 0): "
             "give amplitudes in [data] displacement_column (the data may hold signed "
             "displacements)");
  }
  // The data against the range of the prior predictive's peaks, not its median: a prior over
  // clamp patterns spreads the peaks over orders of magnitude (most patterns fix clamps near the
  // load), and data from a pattern with free clamps there lie far above the median in the right
  // units (issue 35: 36.6x on the 45 cm example in µm, not normalised). A unit mistake is a
  // factor of 1e3 or more (µm, mm, m), or 1e2 (cm); the 5-95 % range keeps a stray curve out.
  if (!v.normalised && !peaks.empty() && o.data_peak > 0.0) {
    const double high = o.simulated_peak_high;
    const double low = o.simulated_peak_low;
    const double above = high > 0.0 ? o.data_peak / high : kNaN;
    const double below_low = low > 0.0 ? low / o.data_peak : kNaN;
    if (above > options.scale_factor || below_low > options.scale_factor) {
      const bool too_high = above > options.scale_factor;
      Warn(checks.before,
           "units_mismatch",
           prefix + "the measured peak (" + Short(o.data_peak) + ") is " +
               (too_high ? Short(above) + " times the top"
                         : "1/" + Short(below_low) + " of the bottom") +
               " of the 5-95 % range of the simulated peaks at the measured positions (" +
               Short(low) + "-" + Short(high) +
               "): the data and the model are in different units; check [data] "
               "displacement_unit against the model's output (m), or set [data] normalise = "
               "true");
    }
  }
}

// The plain (kThreshold) components of the slice as (threshold slot, name): the slots count
// every non-indicator component of the run in order.
std::vector<std::pair<std::size_t, std::string>> PlainSlots(const RunMetadata& m,
                                                            const ExperimentSlice& slice,
                                                            bool* noise_aware) {
  std::vector<std::pair<std::size_t, std::string>> out;
  std::size_t slot = 0;
  *noise_aware = false;
  for (std::size_t c = 0; c < m.distance_components.size(); ++c) {
    const DistanceComponent& dc = m.distance_components[c];
    if (dc.kind == ComponentKind::kIndicator) continue;
    const bool mine = c >= slice.first_component && c < slice.first_component + slice.components;
    if (mine && dc.kind == ComponentKind::kThreshold) out.emplace_back(slot, dc.name);
    if (mine && dc.kind == ComponentKind::kNegLogLikelihood) *noise_aware = true;
    ++slot;
  }
  return out;
}

// The best curve's goodness of fit (FitVerdict): against the noise-aware components' sigmas over
// their windows, or the data's estimate over every point. A sigma stated is taken as known (a
// chi-square test); the estimate carries its own scatter, as a chi-square with (N - 5) / 2.91
// degrees of freedom for N points (the fifth differences of N points give N - 5 pseudo-residuals
// whose overlap, autocorrelations -0.83, 0.48, -0.18, 0.04 and -0.004, inflates the variance of
// their mean square by 1 + 2 sum rho^2 = 2.91: a scatter of 23 % on 33 points and 36 % on 16,
// near the 20 % and 35 % measured, docs/algorithm.md), so ratio^2 gets an F test; the amplitude
// estimate's degrees of freedom are its own (NoiseLevel::dof). Without it the estimate's scatter,
// and the Gaussian estimate's low reading on amplitudes folded at zero (0.73 of the truth on the
// 45 cm example), would call correct fits poor. Between "poor" and "good", "doubtful" (p < 0.05):
// 1.35 sigma over 91 points is not a good fit against any estimate (issue 33).
FitVerdict Verdict(const ExperimentView& v,
                   const std::vector<double>& best,
                   double best_rms,
                   const NoiseLevel& noise,
                   const FitCheckOptions& options) {
  const double estimate = noise.value;
  FitVerdict fit;
  fit.experiment = v.slice.name;
  fit.noise_sigma = estimate;
  const std::vector<const StatedNoise*> stated = StatedOf(v.slice, options);
  bool estimated = stated.empty();
  double ss = 0.0;
  double chi2 = 0.0;
  // r^2 / sigma^2, with sigma = 0 (an estimate at the level of rounding) as no noise at all.
  auto scaled = [](double r2, double sigma) {
    if (sigma > 0.0) return r2 / (sigma * sigma);
    return r2 > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
  };
  if (stated.empty()) {
    fit.points = v.y.size();
    ss = static_cast<double>(fit.points) * best_rms * best_rms;
    fit.sigma = estimate;
    chi2 = scaled(ss, estimate);
  } else {
    for (const StatedNoise* s : stated) {
      estimated = estimated || !s->sigma_noise;
      const double sigma = SigmaOf(*s, estimate);
      for (std::size_t j = 0; j < v.x.size(); ++j) {
        if (v.x[j] < s->from - kPositionSlack || v.x[j] > s->to + kPositionSlack) continue;
        const double r2 = (v.y[j] - best[j]) * (v.y[j] - best[j]);
        ss += r2;
        chi2 += scaled(r2, sigma);
        ++fit.points;
      }
    }
    fit.sigma = stated.size() == 1 ? SigmaOf(*stated.front(), estimate) : kNaN;
  }
  const auto n = static_cast<double>(std::max<std::size_t>(fit.points, 1));
  fit.best_rms = std::sqrt(ss / n);
  fit.chi2 = chi2;
  fit.ratio = std::sqrt(chi2 / n);
  if (std::isnan(fit.sigma)) fit.sigma = fit.ratio > 0.0 ? fit.best_rms / fit.ratio : kNaN;
  fit.sigma_source = estimated ? "estimated" : "stated";
  fit.sigma_dof = estimated ? noise.dof : std::numeric_limits<double>::infinity();
  fit.p_value =
      estimated ? FUpperTail(fit.ratio * fit.ratio, n, fit.sigma_dof) : ChiSquareUpperTail(chi2, n);
  if (fit.ratio > options.poor_fit_ratio || fit.p_value < options.poor_fit_p) {
    fit.verdict = "poor";
  } else {
    fit.verdict = fit.p_value < options.doubtful_fit_p ? "doubtful" : "good";
  }
  return fit;
}

using PlainSlotList = std::vector<std::pair<std::size_t, std::string>>;

// threshold_stalled: the last complete waves barely cut a plain threshold.
void CheckThresholdStalled(const std::string& prefix,
                           const PlainSlotList& plain,
                           const RunHistory& h,
                           const FitCheckOptions& options,
                           FitChecks& checks) {
  std::vector<const WaveRecord*> complete;
  for (const WaveRecord& w : h.waves) {
    if (w.complete) complete.push_back(&w);
  }
  const auto back = static_cast<std::size_t>(options.stall_waves);
  if (h.summary.termination != Termination::kTargetReached && complete.size() > back) {
    for (const auto& [slot, name] : plain) {
      const WaveRecord& before = *complete[complete.size() - 1 - back];
      const WaveRecord& last = *complete.back();
      if (slot >= before.thresholds.size() || slot >= last.thresholds.size()) continue;
      const double a = before.thresholds[slot];
      const double b = last.thresholds[slot];
      if (std::isfinite(a) && std::isfinite(b) && a > 0.0 &&
          b > (1.0 - options.stall_reduction) * a) {
        std::ostringstream message;
        message << prefix << "the threshold of \"" << name << "\" fell only from " << Short(a)
                << " to " << Short(b) << " over the last " << back
                << " complete waves: the sampler gets no closer to the data; likely causes: the "
                   "model cannot reproduce the data (units: [model] length, [data] "
                   "position_unit, displacement_unit, normalise; the load: [model.load]), or the "
                   "threshold has reached the noise (then more waves add nothing: [sampler] "
                   "waves)";
        Warn(checks.after, "threshold_stalled", message.str());
      }
    }
  }
}

// poor_fit: the best curve's verdict, against the stated sigma or the noise estimate.
void WarnPoorFit(const std::string& prefix,
                 const FitVerdict& fit,
                 double noise,
                 FitChecks& checks) {
  const std::string against = fit.sigma_source == "stated"
                                  ? "the noise-aware components' sigma (" + Short(fit.sigma) +
                                        "; the noise estimated from the data is " + Short(noise) +
                                        ")"
                                  : "the noise estimated from the data (" + Short(noise) + ")";
  const std::string cause =
      fit.sigma_source == "stated"
          ? "the stated sigma is too small for what the model can reach, and the posterior "
            "too narrow ([metric] sigma_noise, sigma_model for the model's discrepancy), or "
            "the model cannot reproduce the data; likely causes: "
          : "the model cannot reproduce the data; likely causes: ";
  Warn(checks.after,
       "poor_fit",
       prefix + "the best accepted curve misses the data by RMS " + Short(fit.best_rms) + ", " +
           Short(fit.ratio) + " times " + against + " over " + std::to_string(fit.points) +
           " points, as large by noise alone with probability " + Short(fit.p_value) + ": " +
           cause +
           "units ([model] length, [data] position_unit, displacement_unit, normalise), the "
           "load ([model.load] x, amplitude), the measured window ([data] window), or too few "
           "waves");
}

// The curves of the final wave's particles at the data's positions (those that keep one), with
// their weights' positive part: a multi-fidelity wave's signed weights as its posterior draws use
// them (a quantile needs a distribution; docs/history.md, "Checks").
void FinalCurves(const ExperimentView& v,
                 const WaveRecord& final_wave,
                 std::vector<std::vector<double>>* curves,
                 std::vector<double>* weights) {
  for (const Particle& p : final_wave.particles) {
    std::vector<double> curve = CurveAt(v, p);
    if (curve.empty()) continue;
    curves->push_back(std::move(curve));
    weights->push_back(std::max(p.weight, 0.0));
  }
}

// threshold_below_noise: the final wave's curves all fit within L log-likelihood units of the
// best of them (sums of squares within 2 sigma^2 L), and earlier waves hold curves just as good
// that it no longer accepts: the threshold rejects what the noise cannot tell apart. The caller
// checks it only with a good fit (else the model, not the noise, is what the threshold meets) and
// a resolved noise (else its estimate may be too high).
void CheckThresholdBelowNoise(const std::string& prefix,
                              const ExperimentView& v,
                              const RunHistory& h,
                              const WaveRecord* final_wave,
                              double best_rms,
                              double worst_rms,
                              double noise,
                              const FitCheckOptions& options,
                              FitChecks& checks) {
  const auto n = static_cast<double>(v.y.size());
  const double unit = 2.0 * noise * noise;
  const double best_ss = n * best_rms * best_rms;
  const double worst_ss = n * worst_rms * worst_rms;
  const double band = (worst_ss - best_ss) / unit;
  std::set<std::pair<std::vector<std::uint8_t>, std::vector<double>>> accepted;
  for (const Particle& q : final_wave->particles) accepted.emplace(q.theta.bits, q.theta.reals);
  std::size_t dropped = 0;
  for (const WaveRecord& w : h.waves) {
    if (&w == final_wave) continue;
    for (const Particle& p : w.particles) {
      const std::vector<double> curve = CurveAt(v, p);
      if (curve.empty()) continue;
      const double rms = Rms(curve, v.y);
      const double ss = n * rms * rms;
      if (ss > worst_ss && ss <= best_ss + options.overfit_loglik * unit &&
          accepted.count({p.theta.bits, p.theta.reals}) == 0) {
        ++dropped;
      }
    }
  }
  if (band < options.overfit_loglik && dropped > 0) {
    Warn(checks.after,
         "threshold_below_noise",
         prefix + "the plain threshold has fallen below the noise: the final wave's curves fit " +
             "the data within " + Short(band) + " log-likelihood units of the best (RMS " +
             Short(best_rms) + " to " + Short(worst_rms) + ", sigma " + Short(noise) +
             " estimated from the data) and it rejects " + std::to_string(dropped) +
             " earlier particles the noise cannot tell from them, so the posterior is "
             "overconfident; use [metric] noise = \"gaussian\" (the noise-aware acceptance) or "
             "fewer [sampler] waves");
  }
}

// After sampling: the final complete wave's curves against the data and the noise.
void CheckAfter(const RunMetadata& m,
                const ExperimentView& v,
                const RunHistory& h,
                const FitCheckOptions& options,
                FitChecks& checks) {
  const std::string prefix = Prefix(v.slice.name);
  const NoiseLevel noise = NoiseOf(v, options);
  checks.noise.push_back(noise);

  bool noise_aware = false;
  const auto plain = PlainSlots(m, v.slice, &noise_aware);
  CheckThresholdStalled(prefix, plain, h, options, checks);
  const WaveRecord* final_wave = FinalWave(h);
  if (final_wave == nullptr || v.y.empty()) return;
  std::vector<std::vector<double>> curves;
  std::vector<double> weights;
  FinalCurves(v, *final_wave, &curves, &weights);
  if (curves.empty()) {
    Note(checks.after,
         "no_curves",
         prefix +
             "the history keeps no simulated curves, so the fit is not checked ([output] "
             "keep_simulated_curves = true keeps them)");
    return;
  }
  PredictiveCheck pc;
  pc.experiment = v.slice.name;
  pc.wave = final_wave->wave + 1;
  pc.positions = v.x;
  pc.measured = v.y;
  std::size_t best = 0;
  double best_rms = std::numeric_limits<double>::infinity();
  double worst_rms = 0.0;
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const double rms = Rms(curves[i], v.y);
    if (rms < best_rms) {
      best_rms = rms;
      best = i;
    }
    worst_rms =
        std::max(worst_rms, std::isnan(rms) ? std::numeric_limits<double>::infinity() : rms);
  }
  std::vector<std::pair<double, double>> column(curves.size());
  for (std::size_t j = 0; j < v.x.size(); ++j) {
    for (std::size_t i = 0; i < curves.size(); ++i) column[i] = {curves[i][j], weights[i]};
    pc.band_low.push_back(WeightedQuantile(column, options.band_low));
    pc.median.push_back(WeightedQuantile(column, 0.5));
    pc.band_high.push_back(WeightedQuantile(column, options.band_high));
    pc.best.push_back(curves[best][j]);
    pc.residuals.push_back(v.y[j] - curves[best][j]);
  }
  checks.predictive.push_back(std::move(pc));

  if (!(noise.value >= 0.0) || !std::isfinite(best_rms)) return;
  // The estimate assumes a profile smooth at the spacing of the measured points; the best curve,
  // noise-free, says how much the profile itself reads.
  const bool amplitudes = noise.method == kAmplitudeNoiseMethod;
  const double shape =
      amplitudes && std::all_of(
                        curves[best].begin(), curves[best].end(), [](double y) { return y >= 0.0; })
          ? EstimateAmplitudeNoise(v.x, curves[best]).sigma
          : EstimateNoiseSigma(v.x, curves[best]);
  checks.noise.back().shape = shape;
  const bool resolved = shape <= options.shape_fraction * noise.value;
  if (!resolved) {
    Note(checks.after,
         "noise_unresolved",
         prefix + "the noise estimated from the data (" + Short(noise.value) +
             ") may be the profile's own detail: the best curve, noise-free, reads " +
             Short(shape) +
             " by the same estimate (too few measured points per feature of the profile); the "
             "fit is judged against it all the same and threshold_below_noise is not checked; "
             "give [metric] sigma_noise if the noise is known");
  }
  checks.fit.push_back(Verdict(v, curves[best], best_rms, noise, options));
  const FitVerdict& fit = checks.fit.back();
  if (fit.verdict == "poor") WarnPoorFit(prefix, fit, noise.value, checks);
  // Not with a poor fit, nor when the noise is not resolved (CheckThresholdBelowNoise).
  if (!noise_aware && !plain.empty() && noise.value > 0.0 && resolved && fit.verdict == "good") {
    CheckThresholdBelowNoise(
        prefix, v, h, final_wave, best_rms, worst_rms, noise.value, options, checks);
  }
}

void MessagesJson(std::ostream& out,
                  const std::vector<CheckMessage>& messages,
                  const std::string& pad) {
  out << "[";
  for (std::size_t i = 0; i < messages.size(); ++i) {
    out << (i ? "," : "") << "\n"
        << pad << "  {\"severity\": " << JsonString(messages[i].severity)
        << ", \"code\": " << JsonString(messages[i].code)
        << ", \"message\": " << JsonString(messages[i].message) << "}";
  }
  if (!messages.empty()) out << "\n" << pad;
  out << "]";
}

}  // namespace

bool FitCheckOptions::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool FitCheckOptions::IsValid(ValidationError* error) const {
  // No owner and no value: "scale_factor must be > 1".
  auto fail = [error](const std::string& field, const char* constraint) {
    if (error != nullptr) *error = {"", field, "", constraint};
    return false;
  };
  if (!(scale_factor > 1.0)) return fail("scale_factor", "must be > 1");
  if (!(poor_fit_ratio > 0.0)) return fail("poor_fit_ratio", "must be > 0");
  if (!(poor_fit_p >= 0.0 && poor_fit_p < 1.0)) return fail("poor_fit_p", "must lie in [0, 1)");
  if (!(doubtful_fit_p >= poor_fit_p && doubtful_fit_p < 1.0)) {
    return fail("doubtful_fit_p", "must lie in [poor_fit_p, 1)");
  }
  if (!(noise_below_fraction >= 0.0)) return fail("noise_below_fraction", "must be >= 0");
  for (std::size_t k = 0; k < stated_noise.size(); ++k) {
    const StatedNoise& s = stated_noise[k];
    const std::string at = "stated_noise[" + std::to_string(k) + "].";
    if (s.sigma_noise && !(*s.sigma_noise > 0.0 && std::isfinite(*s.sigma_noise))) {
      return fail(at + "sigma_noise", "must be finite and > 0");
    }
    if (!(s.sigma_model >= 0.0 && std::isfinite(s.sigma_model))) {
      return fail(at + "sigma_model", "must be finite and >= 0");
    }
    if (!(s.from <= s.to)) return fail(at + "from", "must be <= to");
  }
  if (!(stall_reduction > 0.0 && stall_reduction < 1.0)) {
    return fail("stall_reduction", "must lie in (0, 1)");
  }
  if (stall_waves < 1) return fail("stall_waves", "must be >= 1");
  if (!(negative_fraction >= 0.0 && negative_fraction < 1.0)) {
    return fail("negative_fraction", "must lie in [0, 1)");
  }
  if (!(shape_fraction > 0.0)) return fail("shape_fraction", "must be > 0");
  if (!(overfit_loglik >= 0.0)) return fail("overfit_loglik", "must be >= 0");
  if (!(band_low >= 0.0 && band_low < band_high && band_high <= 1.0)) {
    return fail("band_low", "< band_high must lie in [0, 1]");
  }
  return true;
}

FitChecks ComputeBeforeChecks(const RunMetadata& metadata,
                              const WaveRecord* first_wave,
                              const FitCheckOptions& options) {
  std::string why;
  COMBABC_CHECK(options.IsValid(&why));
  FitChecks checks;
  for (const ExperimentSlice& slice : ExperimentSlices(metadata)) {
    CheckBefore(metadata, ViewOf(metadata, slice), first_wave, options, checks);
  }
  return checks;
}

FitChecks ComputeFitChecks(const RunMetadata& metadata,
                           const RunHistory& history,
                           const FitCheckOptions& options) {
  FitChecks checks = ComputeBeforeChecks(
      metadata, history.waves.empty() ? nullptr : &history.waves.front(), options);
  for (const ExperimentSlice& slice : ExperimentSlices(metadata)) {
    CheckAfter(metadata, ViewOf(metadata, slice), history, options, checks);
  }
  // mode_loss: a wave's proposal gave a heavy pattern of the previous wave negligible probability
  // (docs/algorithm.md, "Mode loss").
  for (const WaveRecord& w : history.waves) {
    const std::string warning = ModeLossWarning(w);
    if (!warning.empty()) Warn(checks.after, "mode_loss", warning);
  }
  return checks;
}

std::string FormatBeforeChecks(const FitChecks& checks, const std::string& position_unit) {
  std::ostringstream out;
  for (const ExperimentOverview& o : checks.overview) {
    out << "checks: " << Prefix(o.experiment) << o.points << " measured points at "
        << Short(o.position_low) << "-" << Short(o.position_high) << " " << position_unit
        << ", values " << Short(o.data_low) << " to " << Short(o.data_peak) << " (peak); ";
    const char* curves = o.prior_predictive ? "prior predictive" : "first wave's accepted";
    if (std::isnan(o.simulated_peak_low)) {
      out << "no simulated curves stored";
    } else if (o.normalised) {
      // Every peak is 1 by construction: a range would say nothing.
      out << "data and " << curves << " curves compared normalised to peak 1";
    } else {
      out << curves << " peaks " << Short(o.simulated_peak_low) << "-"
          << Short(o.simulated_peak_high) << " (5-95 %)";
    }
    out << "\n";
  }
  for (const CheckMessage& m : checks.before) {
    out << m.severity << " [" << m.code << "]: " << m.message << "\n";
  }
  return out.str();
}

std::string FormatAfterChecks(const FitChecks& checks) {
  std::ostringstream out;
  for (const FitVerdict& f : checks.fit) {
    out << "checks: " << Prefix(f.experiment) << "noise sigma " << Short(f.noise_sigma)
        << " (estimated), best fit RMS " << Short(f.best_rms) << " = " << Short(f.ratio);
    if (f.sigma_source == "stated") {
      out << " x the stated sigma " << Short(f.sigma) << " over " << f.points
          << " points (chi-square p = " << Short(f.p_value) << ")";
    } else {
      out << " sigma over " << f.points << " points (F test p = " << Short(f.p_value) << ")";
    }
    out << ": " << f.verdict << "\n";
  }
  for (const CheckMessage& m : checks.after) {
    out << m.severity << " [" << m.code << "]: " << m.message << "\n";
  }
  return out.str();
}

std::string FormatFitChecks(const FitChecks& checks, const std::string& position_unit) {
  return FormatBeforeChecks(checks, position_unit) + FormatAfterChecks(checks);
}

std::string FitChecksJson(const FitChecks& checks, int indent) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  const std::string in = pad + "  ";
  std::ostringstream out;
  out << "{\n" << in << "\"before\": ";
  MessagesJson(out, checks.before, in);
  out << ",\n" << in << "\"after\": ";
  MessagesJson(out, checks.after, in);
  out << ",\n" << in << "\"noise_sigma\": [";
  for (std::size_t i = 0; i < checks.noise.size(); ++i) {
    const NoiseLevel& n = checks.noise[i];
    out << (i ? ", " : "") << "{\"experiment\": " << JsonString(n.experiment)
        << ", \"value\": " << JsonNumber(n.value) << ", \"method\": " << JsonString(n.method)
        << ", \"shape\": " << JsonNumber(n.shape) << "}";
  }
  out << "],\n" << in << "\"fit\": [";
  for (std::size_t i = 0; i < checks.fit.size(); ++i) {
    const FitVerdict& f = checks.fit[i];
    out << (i ? ", " : "") << "{\"experiment\": " << JsonString(f.experiment)
        << ", \"best_rms\": " << JsonNumber(f.best_rms)
        << ", \"noise_sigma\": " << JsonNumber(f.noise_sigma)
        << ", \"sigma\": " << JsonNumber(f.sigma)
        << ", \"sigma_source\": " << JsonString(f.sigma_source) << ", \"points\": " << f.points
        << ", \"ratio\": " << JsonNumber(f.ratio) << ", \"chi2\": " << JsonNumber(f.chi2)
        << ", \"sigma_dof\": " << JsonNumber(f.sigma_dof)
        << ", \"p_value\": " << JsonNumber(f.p_value) << ", \"verdict\": " << JsonString(f.verdict)
        << "}";
  }
  out << "],\n" << in << "\"predictive\": [";
  for (std::size_t i = 0; i < checks.predictive.size(); ++i) {
    const PredictiveCheck& p = checks.predictive[i];
    const std::string row = ",\n" + in + "   ";
    out << (i ? "," : "") << "\n"
        << in << "  {\"experiment\": " << JsonString(p.experiment) << ", \"wave\": " << p.wave
        << row << "\"positions_m\": " << JsonArray(p.positions) << row
        << "\"measured\": " << JsonArray(p.measured) << row
        << "\"band_low\": " << JsonArray(p.band_low) << row
        << "\"band_high\": " << JsonArray(p.band_high) << row
        << "\"median\": " << JsonArray(p.median) << row << "\"best\": " << JsonArray(p.best) << row
        << "\"residuals\": " << JsonArray(p.residuals) << "}";
  }
  if (!checks.predictive.empty()) out << "\n" << in;
  out << "]\n" << pad << "}";
  return out.str();
}

}  // namespace combabc
