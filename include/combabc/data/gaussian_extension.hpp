#pragma once
// Gaussian-fit extension of a measured profile toward the load (paper section 5, the 70 cm data):
// the LDV data start a few centimetres from the shaker, so the paper fitted
//   y(x) = a * exp(-(x - x0)^2 / (2 s^2))          (+ c with fit_offset)
// centred at the known impact position x0 to the measured points nearest the impact, and used the
// fitted curve to synthesise the missing stretch between the impact and the first measured point.
#include <span>
#include <vector>

namespace combabc {

struct GaussianExtensionOptions {
  bool enabled = false;
  // x0, the known load (impact) position, metres. Must lie outside the measured range.
  double impact_position = 0.0;
  // k, the number of measured points nearest the impact used for the fit; >= 2 (>= 3 with
  // fit_offset): the model has two free parameters (three with the offset).
  int fit_points = 3;
  // Spacing of the synthesised points, metres; > 0.
  double spacing = 0.01;
  // Also fit a constant offset c (the profile need not decay to zero).
  bool fit_offset = false;
};

struct GaussianFit {
  double centre = 0.0;         // x0, metres (fixed, not fitted)
  double amplitude = 0.0;      // a, in the displacement's unit
  double width = 0.0;          // s > 0, metres
  double offset = 0.0;         // c (0 unless fit_offset)
  double residual_norm = 0.0;  // ||y - model|| at the solution, over the fitted points
  int iterations = 0;
  bool converged = false;

  double operator()(double x) const;
};

// Least-squares fit of the Gaussian above, centre fixed at `centre`, by Levenberg-Marquardt
// (Eigen's unsupported NonLinearOptimization module, analytic Jacobian). Needs at least 2 points
// (3 with fit_offset). Throws combabc::Error(kData) if the points cannot determine a Gaussian
// (fewer points than parameters, non-finite values, no positive value).
GaussianFit FitGaussian(std::span<const double> x,
                        std::span<const double> y,
                        double centre,
                        bool fit_offset);

// Most points an extension may synthesise (docs/config.md, "Limits"); the paper's needs about 5.
inline constexpr int kMaxSyntheticPoints = 100000;

struct GaussianExtension {
  GaussianFit fit;
  std::vector<double> positions;  // synthesised positions, metres, ascending
  std::vector<double> values;     // fitted values there
};

// Fits the options.fit_points measured points nearest options.impact_position and synthesises
// points from the impact toward the nearest measured point, every options.spacing metres,
// stopping at least spacing/2 short of that measured point so no synthetic point duplicates or
// crowds a measurement. positions must be strictly increasing (metres). Throws
// combabc::Error(kData) if the impact lies inside the measured range, the fit fails, or more than
// kMaxSyntheticPoints points would be synthesised.
GaussianExtension ExtendWithGaussian(const GaussianExtensionOptions& options,
                                     std::span<const double> positions,
                                     std::span<const double> values);

}  // namespace combabc
