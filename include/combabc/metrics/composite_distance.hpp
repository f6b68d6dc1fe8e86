#pragma once
// The paper's distances (Eqs. 4-7) as one combabc::Distance: a list of components evaluated
// against the measured profile, each written to its own slot of the distance vector (Eq. 6 is
// vector-valued; a candidate is accepted when every component passes).
#include <cstddef>
#include <span>
#include <vector>

#include "combabc/distances/distance.hpp"
#include "combabc/metrics/metric_component.hpp"
#include "combabc/metrics/noise_estimate.hpp"

namespace combabc {

// Where the maximum that normalises Y* is taken.
enum class NormaliseOver {
  // Over the measured positions (Y* interpolated there): the same support the data's own maximum
  // came from, so Y and Y* are scaled alike even when the peak lies outside the measured window
  // (the paper's 45 cm data start 3 cm from the load).
  kData,
  // Over the whole simulator output.
  kOutput,
};

struct CompositeDistanceOptions {
  // Divide each simulated profile by its maximum absolute value before comparing (paper
  // section 5: both curves normalised to [0, 1]). Set it to match the measured data's
  // normalisation (DataConfig::normalise).
  bool normalise_simulated = true;
  NormaliseOver normalise_over = NormaliseOver::kData;
};

class CompositeDistance : public Distance {
 public:
  // data_positions (metres, strictly increasing) and data_values: the measured profile Y, already
  // normalised if it is to be. output_positions (metres, strictly increasing): where the
  // simulator reports Y*; Y* is resampled onto the data positions by linear interpolation, with
  // the indices and weights computed here once. Throws combabc::Error(kConfig, field =
  // "metric.component[i]") if a window reaches outside the simulator's output positions or the
  // data positions, holds too few data points, if the measured area of an area component is not
  // positive, or if the measured data themselves fail a rise / fall indicator (Eq. 7) -- such an
  // indicator would reject the true configuration.
  CompositeDistance(std::vector<MetricComponentConfig> components,
                    std::span<const double> data_positions,
                    std::span<const double> data_values,
                    std::span<const double> output_positions,
                    CompositeDistanceOptions options = {});

  std::vector<DistanceComponent> components() const override;
  // simulated.size() must equal the number of output positions. If the simulated profile's
  // maximum is zero or not finite when normalising, every threshold component is +inf and every
  // indicator 0, so the candidate is rejected rather than compared as NaN.
  void Evaluate(std::span<const double> simulated, std::span<double> out) const override;

  // One schedule per threshold or likelihood component, in component order: what
  // SmcOptions::thresholds wants.
  std::vector<ThresholdSchedule> threshold_schedules() const;
  // Component k's total sigma (a noise model; sigma_noise estimated if not given), or 0.
  double noise_sigma(std::size_t k) const { return compiled_.at(k).sigma; }
  const std::vector<MetricComponentConfig>& configs() const { return configs_; }
  std::size_t output_size() const { return output_size_; }

 private:
  // Y*(x) = (1 - w) Y*[i] + w Y*[i + 1].
  struct Sample {
    std::size_t index = 0;
    double weight = 0.0;
  };
  struct Compiled {
    MetricType type = MetricType::kLeastSquares;
    std::vector<double> observed;   // y_j inside the window
    std::vector<double> positions;  // x_j inside the window (area: trapezoid widths)
    std::vector<Sample> samples;    // where to read y*_j (rise / fall: the two endpoints)
    double observed_area = 0.0;     // area: A(Y)
    double sigma = 0.0;             // noise model: sqrt(sigma_noise^2 + sigma_model^2)
    bool folded = false;            // folded_normal
    // folded_normal: -log max_mu f(y_j; mu, sigma), the normaliser of each point's likelihood.
    std::vector<double> best_energy;
  };

  double Interpolate(std::span<const double> simulated, const Sample& s, double scale) const;

  std::vector<MetricComponentConfig> configs_;
  std::vector<Compiled> compiled_;
  std::vector<Sample> data_samples_;  // Y* at every measured position (NormaliseOver::kData)
  std::size_t output_size_ = 0;
  CompositeDistanceOptions options_;
};

}  // namespace combabc
