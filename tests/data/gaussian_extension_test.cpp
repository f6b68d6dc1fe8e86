#include "combabc/data/gaussian_extension.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

constexpr double kParameterTol = 1e-6;

std::vector<double> Gaussian(
    const std::vector<double>& x, double a, double x0, double s, double c = 0.0) {
  std::vector<double> y;
  y.reserve(x.size());
  for (double xi : x) y.push_back(a * std::exp(-(xi - x0) * (xi - x0) / (2 * s * s)) + c);
  return y;
}

TEST(GaussianExtension, FitRecoversExactGaussian) {
  const std::vector<double> x = {0.74, 0.75, 0.76};
  const auto y = Gaussian(x, 2.5e-6, 0.70, 0.035);
  const GaussianFit fit = FitGaussian(x, y, 0.70, false);
  EXPECT_TRUE(fit.converged);
  EXPECT_NEAR(fit.amplitude, 2.5e-6, kParameterTol * 2.5e-6);
  EXPECT_NEAR(fit.width, 0.035, kParameterTol);
  EXPECT_NEAR(fit.centre, 0.70, 0.0);
  EXPECT_LT(fit.residual_norm, 1e-15);
}

TEST(GaussianExtension, FitRecoversOffset) {
  const std::vector<double> x = {0.74, 0.75, 0.76, 0.77, 0.78};
  const auto y = Gaussian(x, 1.0, 0.70, 0.04, 0.1);
  const GaussianFit fit = FitGaussian(x, y, 0.70, true);
  EXPECT_NEAR(fit.amplitude, 1.0, kParameterTol);
  EXPECT_NEAR(fit.width, 0.04, kParameterTol);
  EXPECT_NEAR(fit.offset, 0.1, kParameterTol);
}

TEST(GaussianExtension, ToleratesANegativeReading) {
  // A non-positive reading cannot enter the log-linear start; the LM fit must still use it.
  const std::vector<double> x = {0.60, 0.62, 0.64, 0.66};
  auto y = Gaussian(x, 1.0, 0.70, 0.05);
  y[0] = -1e-3;  // a slightly negative reading
  const GaussianFit fit = FitGaussian(x, y, 0.70, false);
  EXPECT_TRUE(fit.converged);
  EXPECT_NEAR(fit.width, 0.05, 5e-3);
}

TEST(GaussianExtension, TooFewPointsIsADataError) {
  const std::vector<double> x = {0.74};
  const std::vector<double> y = {1.0};
  try {
    FitGaussian(x, y, 0.70, false);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kData);
  }
}

TEST(GaussianExtension, SynthesisedProfileIsContinuousWithTheData) {
  std::vector<double> x;
  for (int cm = 74; cm <= 89; ++cm) x.push_back(cm * 0.01);
  const auto y = Gaussian(x, 1.0, 0.70, 0.03);
  GaussianExtensionOptions options;
  options.enabled = true;
  options.impact_position = 0.70;
  options.fit_points = 3;
  options.spacing = 0.01;
  const GaussianExtension ext = ExtendWithGaussian(options, x, y);
  ASSERT_EQ(ext.positions.size(), 4u);
  EXPECT_NEAR(ext.positions.front(), 0.70, 1e-12);
  EXPECT_NEAR(ext.positions.back(), 0.73, 1e-12);
  // Continuity: the fitted curve passes through the measured points it was fitted to, and the
  // step from the last synthetic point to the first measurement matches the underlying profile.
  EXPECT_NEAR(ext.fit(x[0]), y[0], 1e-9);
  const auto expected = Gaussian({0.73}, 1.0, 0.70, 0.03);
  EXPECT_NEAR(ext.values.back(), expected[0], 1e-9);
  EXPECT_NEAR(ext.values.front(), 1.0, 1e-6);
}

TEST(GaussianExtension, ImpactAboveTheDataSynthesisesDescendingSide) {
  std::vector<double> x = {0.40, 0.41, 0.42};
  const auto y = Gaussian(x, 1.0, 0.45, 0.02);
  GaussianExtensionOptions options;
  options.impact_position = 0.45;
  options.fit_points = 3;
  options.spacing = 0.01;
  const GaussianExtension ext = ExtendWithGaussian(options, x, y);
  ASSERT_EQ(ext.positions.size(), 3u);  // 0.43, 0.44, 0.45 ascending
  EXPECT_NEAR(ext.positions.front(), 0.43, 1e-12);
  EXPECT_NEAR(ext.positions.back(), 0.45, 1e-12);
}

TEST(GaussianExtension, ImpactInsideTheDataIsAnError) {
  const std::vector<double> x = {0.40, 0.50, 0.60};
  const std::vector<double> y = {0.2, 1.0, 0.3};
  GaussianExtensionOptions options;
  options.impact_position = 0.45;
  EXPECT_THROW(ExtendWithGaussian(options, x, y), Error);
}

// Regression: the number of synthetic points was a double cast to int, which overflowed (undefined
// behaviour) for a tiny spacing or a far impact; it is range-checked before the conversion.
TEST(GaussianExtension, TooManySyntheticPointsIsADataErrorNotAnOverflow) {
  const std::vector<double> x = {0.40, 0.41, 0.42};
  const auto y = Gaussian(x, 1.0, 0.45, 0.02);
  for (const auto& [impact, spacing] : {std::pair{0.45, 1e-12},     // 3e10 points
                                        std::pair{1e300, 0.01},     // gap of 1e300 m
                                        std::pair{-1e308, 1e-300},  // inf points
                                        std::pair{0.45, 0.03 / 100001}}) {
    GaussianExtensionOptions options;
    options.impact_position = impact;
    options.spacing = spacing;
    try {
      ExtendWithGaussian(options, x, y);
      ADD_FAILURE() << "no error for impact " << impact << ", spacing " << spacing;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kData);
      EXPECT_NE(std::string(e.what()).find("more than 100000 points"), std::string::npos)
          << e.what();
    }
  }
  // Exactly at the limit is fine: the gap 0.03 m in 99999.5 spacings gives 100000 points.
  GaussianExtensionOptions options;
  options.impact_position = 0.45;
  options.spacing = 0.03 / 99999.5;
  EXPECT_EQ(ExtendWithGaussian(options, x, y).positions.size(),
            static_cast<std::size_t>(kMaxSyntheticPoints));
}

TEST(GaussianExtension, NonFiniteOptionsAreDataErrors) {
  const std::vector<double> x = {0.40, 0.41, 0.42};
  const auto y = Gaussian(x, 1.0, 0.45, 0.02);
  GaussianExtensionOptions options;
  options.impact_position = INFINITY;
  EXPECT_THROW(ExtendWithGaussian(options, x, y), Error);
  options.impact_position = 0.45;
  options.spacing = INFINITY;
  EXPECT_THROW(ExtendWithGaussian(options, x, y), Error);
}

}  // namespace
}  // namespace combabc
