#include "combabc/metrics/composite_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/metrics/folded_normal.hpp"
#include "metrics/window_checks.hpp"

namespace combabc {
namespace {

// Named apart from src/data/'s own kPositionTolerance and Metres, which a unity batch may put in
// the same translation unit.
constexpr double kTolerance = metrics_internal::kPositionTolerance;

std::string Field(std::size_t i) { return metrics_internal::ComponentField(i); }

std::string InMetres(double x) {
  std::ostringstream out;
  out << x << " m";
  return out.str();
}

// A folded_normal component's data are amplitudes: f(y) is 0 below 0, and the estimate reads
// every measured point, so all of them must be >= 0.
void CheckAmplitudes(const MetricComponentConfig& c,
                     std::size_t i,
                     std::span<const double> positions,
                     std::span<const double> values) {
  for (std::size_t j = 0; j < values.size(); ++j) {
    if (values[j] >= 0.0) continue;
    std::ostringstream what;
    what << "noise = \"folded_normal\" models amplitudes (>= 0), but the measured value at "
         << InMetres(positions[j]) << " is " << values[j]
         << ": give amplitudes in [data] displacement_column, or noise = \"gaussian\" for "
            "signed data";
    throw Error(ErrorKind::kConfig, what.str(), {}, c.config_line, Field(i));
  }
}

void CheckIncreasing(std::span<const double> x, const char* what) {
  for (std::size_t i = 1; i < x.size(); ++i) {
    if (!(x[i] > x[i - 1])) {
      throw Error(ErrorKind::kConfig, std::string(what) + " must be strictly increasing");
    }
  }
}

// A noise model's sigma: sigma_noise, or the one estimated from the measured data, combined with
// sigma_model; Error(kConfig) at the component when it is not finite and > 0.
double NoiseSigma(const MetricComponentConfig& c,
                  std::size_t i,
                  bool folded,
                  std::span<const double> data_positions,
                  std::span<const double> data_values) {
  double noise = 0.0;
  if (c.noise.sigma_noise) {
    noise = *c.noise.sigma_noise;
  } else if (data_positions.size() >= 3) {
    noise = folded ? EstimateAmplitudeNoise(data_positions, data_values).sigma
                   : EstimateNoiseSigma(data_positions, data_values);
  }
  const double sigma = std::hypot(noise, c.noise.sigma_model);
  if (!(sigma > 0.0) || !std::isfinite(sigma)) {
    throw Error(ErrorKind::kConfig,
                std::string("the ") + ToString(c.noise.model) + " noise model's sigma is " +
                    std::to_string(sigma) +
                    (c.noise.sigma_noise ? "" : " (estimated from the measured data)") +
                    "; it must be finite and > 0: give sigma_noise or sigma_model",
                {},
                c.config_line,
                Field(i));
  }
  return sigma;
}

// A(Y): the trapezoid area of the measured points in an area component's window; Error(kConfig)
// at the component when it is not positive (Eq. 4 divides by it).
double ObservedArea(const MetricComponentConfig& c,
                    std::size_t i,
                    const std::vector<double>& positions,
                    const std::vector<double>& observed) {
  double area = 0.0;
  for (std::size_t j = 1; j < positions.size(); ++j) {
    area += 0.5 * (observed[j] + observed[j - 1]) * (positions[j] - positions[j - 1]);
  }
  if (!(area > 0.0)) {
    throw Error(ErrorKind::kConfig,
                "the measured area over the window is not positive; Eq. 4 divides by it",
                {},
                c.config_line,
                Field(i));
  }
  return area;
}

}  // namespace

CompositeDistance::CompositeDistance(std::vector<MetricComponentConfig> components,
                                     std::span<const double> data_positions,
                                     std::span<const double> data_values,
                                     std::span<const double> output_positions,
                                     CompositeDistanceOptions options)
    : configs_(std::move(components)), output_size_(output_positions.size()), options_(options) {
  if (configs_.empty()) throw Error(ErrorKind::kConfig, "no components", {}, 0, "metric");
  if (data_positions.size() != data_values.size()) {
    throw Error(ErrorKind::kConfig, "data positions and values differ in length");
  }
  if (output_positions.empty()) {
    throw Error(ErrorKind::kConfig, "the simulator reports no output positions");
  }
  CheckIncreasing(data_positions, "data positions");
  CheckIncreasing(output_positions, "simulator output positions");

  const double out_lo = output_positions.front();
  const double out_hi = output_positions.back();
  // Precompute where Y* is read for position x: the bracketing output indices and weight.
  auto sample_at = [&](double x, std::size_t i) {
    if (x < out_lo - kTolerance || x > out_hi + kTolerance) {
      throw Error(ErrorKind::kConfig,
                  "position " + InMetres(x) + " lies outside the simulator's output positions [" +
                      InMetres(out_lo) + ", " + InMetres(out_hi) + "]",
                  {},
                  configs_[i].config_line,
                  Field(i));
    }
    Sample s;
    if (output_positions.size() == 1) return s;
    const auto upper = std::upper_bound(output_positions.begin(), output_positions.end(), x);
    const auto offset = static_cast<std::size_t>(upper - output_positions.begin());
    s.index = std::min(offset == 0 ? 0 : offset - 1, output_positions.size() - 2);
    const double x0 = output_positions[s.index];
    const double x1 = output_positions[s.index + 1];
    s.weight = std::clamp((x - x0) / (x1 - x0), 0.0, 1.0);
    return s;
  };

  if (options_.normalise_over == NormaliseOver::kData) {
    for (double x : data_positions) {
      // Measured points beyond the simulated range cannot take part in the maximum.
      if (x < out_lo - kTolerance || x > out_hi + kTolerance) continue;
      data_samples_.push_back(sample_at(x, 0));
    }
  }

  for (std::size_t i = 0; i < configs_.size(); ++i) {
    const MetricComponentConfig& c = configs_[i];
    if (!(c.from < c.to) || !std::isfinite(c.from) || !std::isfinite(c.to)) {
      throw Error(ErrorKind::kConfig,
                  "window [" + InMetres(c.from) + ", " + InMetres(c.to) + "] must have from < to",
                  {},
                  c.config_line,
                  Field(i));
    }
    // A window must lie where both Y* and Y exist: past the model's outputs Y* is not simulated,
    // and past the data a component would silently compare fewer points than its window says.
    metrics_internal::CheckWindowWithin(c, i, out_lo, out_hi, "the model's outputs");
    if (!data_positions.empty()) {
      metrics_internal::CheckWindowWithin(
          c, i, data_positions.front(), data_positions.back(), "the measured data");
    }
    Compiled compiled;
    compiled.type = c.type;
    if (c.noise.model != NoiseModel::kNone && c.type != MetricType::kLeastSquares) {
      throw Error(ErrorKind::kConfig,
                  "a noise model applies to least_squares components only",
                  {},
                  c.config_line,
                  Field(i));
    }
    if (c.noise.model != NoiseModel::kNone) {
      compiled.folded = c.noise.model == NoiseModel::kFoldedNormal;
      if (compiled.folded) CheckAmplitudes(c, i, data_positions, data_values);
      compiled.sigma = NoiseSigma(c, i, compiled.folded, data_positions, data_values);
    }
    if (KindOf(c.type) == ComponentKind::kIndicator) {
      if (!data_positions.empty()) {
        metrics_internal::CheckIndicatorHoldsForData(c, i, data_positions, data_values);
      }
      compiled.samples = {sample_at(c.from, i), sample_at(c.to, i)};
    } else {
      for (std::size_t j = 0; j < data_positions.size(); ++j) {
        const double x = data_positions[j];
        if (x < c.from - kTolerance || x > c.to + kTolerance) continue;
        compiled.positions.push_back(x);
        compiled.observed.push_back(data_values[j]);
        compiled.samples.push_back(sample_at(x, i));
        if (compiled.folded) {
          const double y = data_values[j];
          compiled.best_energy.push_back(
              -FoldedNormalLogDensity(y, FoldedNormalBestMean(y, compiled.sigma), compiled.sigma));
        }
      }
      const std::size_t needed = c.type == MetricType::kArea ? 2 : 1;
      if (compiled.positions.size() < needed) {
        throw Error(ErrorKind::kConfig,
                    "window [" + InMetres(c.from) + ", " + InMetres(c.to) + "] holds " +
                        std::to_string(compiled.positions.size()) + " data points; " +
                        ToString(c.type) + " needs at least " + std::to_string(needed),
                    {},
                    c.config_line,
                    Field(i));
      }
      if (c.type == MetricType::kArea) {
        compiled.observed_area = ObservedArea(c, i, compiled.positions, compiled.observed);
      }
    }
    compiled_.push_back(std::move(compiled));
  }
}

std::vector<DistanceComponent> CompositeDistance::components() const {
  std::vector<DistanceComponent> out;
  out.reserve(configs_.size());
  for (const MetricComponentConfig& c : configs_) {
    DistanceComponent d;
    d.name = ComponentName(c);
    d.kind = KindOf(c);
    d.required = 1.0;
    out.push_back(std::move(d));
  }
  return out;
}

std::vector<ThresholdSchedule> CompositeDistance::threshold_schedules() const {
  std::vector<ThresholdSchedule> out;
  for (const MetricComponentConfig& c : configs_) {
    if (KindOf(c) != ComponentKind::kIndicator) out.push_back(c.threshold);
  }
  return out;
}

double CompositeDistance::Interpolate(std::span<const double> simulated,
                                      const Sample& s,
                                      double scale) const {
  const double y0 = simulated[s.index];
  const double y1 = s.weight > 0.0 ? simulated[s.index + 1] : y0;
  return scale * ((1.0 - s.weight) * y0 + s.weight * y1);
}

void CompositeDistance::Evaluate(std::span<const double> simulated, std::span<double> out) const {
  COMBABC_CHECK(simulated.size() == output_size_);
  COMBABC_CHECK(out.size() == compiled_.size());
  double peak = 0.0;
  bool finite = true;
  for (double y : simulated) finite = finite && std::isfinite(y);
  if (options_.normalise_over == NormaliseOver::kData && !data_samples_.empty()) {
    for (const Sample& s : data_samples_) {
      peak = std::max(peak, std::abs(Interpolate(simulated, s, 1.0)));
    }
  } else {
    for (double y : simulated) peak = std::max(peak, std::abs(y));
  }
  double scale = 1.0;
  if (options_.normalise_simulated) scale = peak > 0.0 ? 1.0 / peak : 0.0;
  if (!finite || scale == 0.0) {
    // A blown-up or all-zero simulation cannot be compared; make it fail every component.
    for (std::size_t k = 0; k < compiled_.size(); ++k) {
      out[k] = KindOf(compiled_[k].type) == ComponentKind::kIndicator
                   ? 0.0
                   : std::numeric_limits<double>::infinity();
    }
    return;
  }

  for (std::size_t k = 0; k < compiled_.size(); ++k) {
    const Compiled& c = compiled_[k];
    switch (c.type) {
      case MetricType::kArea: {  // Eq. 4, trapezoid rule on the window's data points
        double area = 0.0;
        double previous = Interpolate(simulated, c.samples[0], scale);
        for (std::size_t j = 1; j < c.samples.size(); ++j) {
          const double current = Interpolate(simulated, c.samples[j], scale);
          area += 0.5 * (current + previous) * (c.positions[j] - c.positions[j - 1]);
          previous = current;
        }
        out[k] = std::abs(c.observed_area - area) / c.observed_area;
        break;
      }
      case MetricType::kLeastSquares: {  // Eq. 5 (and each block of Eq. 6)
        if (c.folded) {
          // -log(pi(y | Y*) / c), c = prod_j max_mu f(y_j; mu): each term >= 0 but for rounding.
          double sum = 0.0;
          for (std::size_t j = 0; j < c.samples.size(); ++j) {
            const double mu = Interpolate(simulated, c.samples[j], scale);
            sum += -FoldedNormalLogDensity(c.observed[j], mu, c.sigma) - c.best_energy[j];
          }
          out[k] = std::max(sum, 0.0);
          break;
        }
        double sum = 0.0;
        for (std::size_t j = 0; j < c.samples.size(); ++j) {
          const double r = Interpolate(simulated, c.samples[j], scale) - c.observed[j];
          sum += r * r;
        }
        // With a gaussian noise model: -log(pi(y | Y*) / c), c = pi at zero residual.
        out[k] = c.sigma > 0.0 ? sum / (2.0 * c.sigma * c.sigma) : sum;
        break;
      }
      case MetricType::kRise: {  // Eq. 7 H1: y*(to) - y*(from) > 0
        const double change = Interpolate(simulated, c.samples[1], scale) -
                              Interpolate(simulated, c.samples[0], scale);
        out[k] = change > 0.0 ? 1.0 : 0.0;
        break;
      }
      case MetricType::kFall: {  // Eq. 7 H2: y*(to) - y*(from) < 0
        const double change = Interpolate(simulated, c.samples[1], scale) -
                              Interpolate(simulated, c.samples[0], scale);
        out[k] = change < 0.0 ? 1.0 : 0.0;
        break;
      }
    }
  }
}

}  // namespace combabc
