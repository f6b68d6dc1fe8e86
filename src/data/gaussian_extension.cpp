#include "combabc/data/gaussian_extension.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <unsupported/Eigen/NonLinearOptimization>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

// Residuals r_i = a g_i + c - y_i with g_i = exp(-d_i^2 / (2 s^2)), d_i = x_i - x0, for the
// parameters p = (a, s) or (a, s, c); the Jacobian is analytic so LM needs no finite differences.
struct GaussianResiduals {
  const Eigen::VectorXd& distance;  // d_i = x_i - x0
  const Eigen::VectorXd& observed;  // y_i
  bool fit_offset;

  int inputs() const { return fit_offset ? 3 : 2; }
  int values() const { return static_cast<int>(observed.size()); }

  int operator()(const Eigen::VectorXd& p, Eigen::VectorXd& residual) const {
    const double offset = fit_offset ? p(2) : 0.0;
    for (Eigen::Index i = 0; i < observed.size(); ++i) {
      const double g = std::exp(-distance(i) * distance(i) / (2.0 * p(1) * p(1)));
      residual(i) = p(0) * g + offset - observed(i);
    }
    return 0;
  }

  int df(const Eigen::VectorXd& p, Eigen::MatrixXd& jacobian) const {
    const double s = p(1);
    for (Eigen::Index i = 0; i < observed.size(); ++i) {
      const double d2 = distance(i) * distance(i);
      const double g = std::exp(-d2 / (2.0 * s * s));
      jacobian(i, 0) = g;                            // dr/da
      jacobian(i, 1) = p(0) * g * d2 / (s * s * s);  // dr/ds
      if (fit_offset) jacobian(i, 2) = 1.0;          // dr/dc
    }
    return 0;
  }
};

// Starting point from the log-linearised model ln y = ln a - d^2 / (2 s^2), a straight line in
// d^2 (exact for noise-free Gaussian samples); falls back to the data's scale when the points are
// not positive and decaying.
Eigen::VectorXd InitialGuess(const Eigen::VectorXd& d, const Eigen::VectorXd& y, bool fit_offset) {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(fit_offset ? 3 : 2);
  p(0) = y.maxCoeff();
  p(1) = std::max(d.cwiseAbs().mean(), 1e-12);
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (Eigen::Index i = 0; i < y.size(); ++i) {
    if (!(y(i) > 0.0)) continue;
    const double u = d(i) * d(i);
    const double v = std::log(y(i));
    sx += u;
    sy += v;
    sxx += u * u;
    sxy += u * v;
    ++n;
  }
  const double denominator = n * sxx - sx * sx;
  if (n >= 2 && denominator > 0.0) {
    const double slope = (n * sxy - sx * sy) / denominator;
    const double intercept = (sy - slope * sx) / n;
    if (slope < 0.0) {
      p(0) = std::exp(intercept);
      p(1) = std::sqrt(-1.0 / (2.0 * slope));
    }
  }
  return p;
}

std::string Metres(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g m", x);
  return text;
}

}  // namespace

double GaussianFit::operator()(double x) const {
  const double d = x - centre;
  return amplitude * std::exp(-d * d / (2.0 * width * width)) + offset;
}

GaussianFit FitGaussian(std::span<const double> x,
                        std::span<const double> y,
                        double centre,
                        bool fit_offset) {
  const std::size_t parameters = fit_offset ? 3 : 2;
  if (x.size() != y.size() || x.size() < parameters) {
    throw Error(ErrorKind::kData,
                "Gaussian fit needs at least " + std::to_string(parameters) + " points, got " +
                    std::to_string(std::min(x.size(), y.size())));
  }
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::VectorXd d(n), observed(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!std::isfinite(x[k]) || !std::isfinite(y[k])) {
      throw Error(ErrorKind::kData, "Gaussian fit: non-finite point");
    }
    d(i) = x[k] - centre;
    observed(i) = y[k];
  }
  if (!(observed.maxCoeff() > 0.0)) {
    throw Error(ErrorKind::kData, "Gaussian fit: no positive value among the fitted points");
  }

  GaussianResiduals residuals{d, observed, fit_offset};
  Eigen::VectorXd p = InitialGuess(d, observed, fit_offset);
  Eigen::LevenbergMarquardt<GaussianResiduals> solver(residuals);
  // Tighter than the sqrt(eps) defaults: the extension feeds a metric compared at 1e-3 levels and
  // the fit is tiny, so polishing to near machine precision costs nothing.
  solver.parameters.ftol = 1e-14;
  solver.parameters.xtol = 1e-14;
  solver.parameters.maxfev = 2000;
  const auto status = solver.minimize(p);

  GaussianFit fit;
  fit.centre = centre;
  fit.amplitude = p(0);
  fit.width = std::abs(p(1));  // the model depends on s^2 only
  fit.offset = fit_offset ? p(2) : 0.0;
  fit.iterations = static_cast<int>(solver.iter);
  // Statuses 1-4 are the convergence tests; 6-8 mean a tolerance hit machine precision, i.e. no
  // further progress is possible (typical for exact data). 0 and 5 are failures.
  using Space = Eigen::LevenbergMarquardtSpace::Status;
  fit.converged = status != Space::ImproperInputParameters &&
                  status != Space::TooManyFunctionEvaluation && status != Space::UserAsked;
  Eigen::VectorXd r(n);
  residuals(p, r);
  fit.residual_norm = r.norm();
  if (!fit.converged || !std::isfinite(fit.amplitude) || !std::isfinite(fit.width) ||
      fit.width <= 0.0) {
    throw Error(ErrorKind::kData,
                "Gaussian fit did not converge (Levenberg-Marquardt status " +
                    std::to_string(static_cast<int>(status)) + ")");
  }
  return fit;
}

GaussianExtension ExtendWithGaussian(const GaussianExtensionOptions& options,
                                     std::span<const double> positions,
                                     std::span<const double> values) {
  if (positions.empty() || positions.size() != values.size()) {
    throw Error(ErrorKind::kData, "Gaussian extension: no data to extend");
  }
  if (!(options.spacing > 0.0) || !std::isfinite(options.spacing)) {
    throw Error(ErrorKind::kData, "Gaussian extension: spacing must be finite and > 0");
  }
  const double x0 = options.impact_position;
  if (!std::isfinite(x0)) {
    throw Error(ErrorKind::kData, "Gaussian extension: impact position must be finite");
  }
  const bool below = x0 < positions.front();
  if (!below && !(x0 > positions.back())) {
    throw Error(ErrorKind::kData,
                "Gaussian extension: impact position " + std::to_string(x0) +
                    " m lies inside the measured range [" + std::to_string(positions.front()) +
                    ", " + std::to_string(positions.back()) + "] m; nothing to synthesise");
  }
  if (options.fit_points < 1 || static_cast<std::size_t>(options.fit_points) > positions.size()) {
    throw Error(ErrorKind::kData,
                "Gaussian extension: fit_points = " + std::to_string(options.fit_points) +
                    " but only " + std::to_string(positions.size()) + " points are available");
  }
  const double nearest = below ? positions.front() : positions.back();
  const double gap = std::abs(nearest - x0);
  // Synthesise x0, x0 +- h, ... while at least h/2 away from the nearest measurement. The count is
  // range-checked as a double before any conversion: a tiny spacing or a far impact would
  // otherwise overflow the integer (undefined behaviour) or exhaust memory.
  const double steps = std::floor((gap - 0.5 * options.spacing) / options.spacing) + 1.0;
  if (!(steps <= static_cast<double>(kMaxSyntheticPoints))) {
    throw Error(ErrorKind::kData,
                "Gaussian extension: spacing " + Metres(options.spacing) + " over the gap of " +
                    Metres(gap) + " to the impact would " + "synthesise more than " +
                    std::to_string(kMaxSyntheticPoints) + " points; use a larger spacing");
  }
  // The impact lies outside the data, so the k nearest points are the k at that end.
  const auto k = static_cast<std::size_t>(options.fit_points);
  const std::size_t first = below ? 0 : positions.size() - k;
  GaussianExtension out;
  out.fit =
      FitGaussian(positions.subspan(first, k), values.subspan(first, k), x0, options.fit_offset);

  const auto count = static_cast<int>(std::max(steps, 0.0));
  for (int i = 0; i < count; ++i) {
    const double step = i * options.spacing;
    out.positions.push_back(below ? x0 + step : x0 - step);
  }
  if (!below) std::reverse(out.positions.begin(), out.positions.end());
  out.values.reserve(out.positions.size());
  for (double x : out.positions) out.values.push_back(out.fit(x));
  return out;
}

}  // namespace combabc
