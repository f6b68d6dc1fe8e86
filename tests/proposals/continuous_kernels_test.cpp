#include "combabc/proposals/continuous_kernels.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal_options.hpp"

namespace combabc {
namespace {

using Vec2 = std::array<double, 2>;
using Mat2 = std::array<double, 4>;  // row-major [a b; b c]

ContinuousPrior Uniform(double low, double high) {
  return {.kind = PriorKind::kUniform, .low = low, .high = high};
}
ContinuousPrior Normal(double mean, double sd) {
  return {.kind = PriorKind::kNormal, .mean = mean, .sd = sd};
}

ParameterSpace Space2(ContinuousPrior x, ContinuousPrior y) {
  return ParameterSpace(BinarySpace::Independent(1), {{"x", x}, {"y", y}});
}
// Normal priors so wide that truncation never matters; their sd (100) only enters the
// regularisation, at 1e-12 x 100^2 = 1e-8 on the diagonal.
ParameterSpace WideSpace() { return Space2(Normal(0.0, 100.0), Normal(0.0, 100.0)); }

Population MakePopulation(const std::vector<Vec2>& r,
                          const std::vector<double>& w,
                          const std::vector<std::uint8_t>& within_next = {}) {
  Population p;
  p.size = r.size();
  p.num_reals = 2;
  for (const Vec2& x : r) p.reals.insert(p.reals.end(), x.begin(), x.end());
  p.weights = w;
  p.within_next = within_next;
  return p;
}

// log N(x; c, S) for 2 x 2 S, by the explicit inverse and determinant.
double LogNormal2(const Vec2& x, const Vec2& c, const Mat2& s) {
  const double det = s[0] * s[3] - s[1] * s[2];
  const double dx = x[0] - c[0], dy = x[1] - c[1];
  const double q = (s[3] * dx * dx - 2.0 * s[1] * dx * dy + s[0] * dy * dy) / det;
  return -std::log(2.0 * M_PI) - 0.5 * std::log(det) - 0.5 * q;
}

double LogMixture(const Vec2& x,
                  const std::vector<Vec2>& c,
                  const std::vector<double>& w,
                  const std::vector<Mat2>& s) {
  double sum = 0.0;
  for (std::size_t j = 0; j < c.size(); ++j) sum += w[j] * std::exp(LogNormal2(x, c[j], s[j]));
  return std::log(sum);
}

Mat2 WeightedCovariance(const std::vector<Vec2>& r, const std::vector<double>& w, Vec2* mean) {
  Vec2 m{0.0, 0.0};
  for (std::size_t j = 0; j < r.size(); ++j) {
    m[0] += w[j] * r[j][0];
    m[1] += w[j] * r[j][1];
  }
  Mat2 s{};
  for (std::size_t j = 0; j < r.size(); ++j) {
    const double dx = r[j][0] - m[0], dy = r[j][1] - m[1];
    s[0] += w[j] * dx * dx;
    s[1] += w[j] * dx * dy;
    s[3] += w[j] * dy * dy;
  }
  s[2] = s[1];
  if (mean) *mean = m;
  return s;
}

// The OLCM of Filippi et al. 2013 straight from its definition: sum over the particles k within
// the next thresholds of w~_k (r_k - r_j)(r_k - r_j)^T.
Mat2 OlcmCovariance(const std::vector<Vec2>& r,
                    const std::vector<double>& w,
                    const std::vector<std::uint8_t>& within,
                    std::size_t j) {
  double total = 0.0;
  for (std::size_t k = 0; k < r.size(); ++k) total += within[k] ? w[k] : 0.0;
  Mat2 s{};
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (!within[k]) continue;
    const double dx = r[k][0] - r[j][0], dy = r[k][1] - r[j][1];
    s[0] += w[k] / total * dx * dx;
    s[1] += w[k] / total * dx * dy;
    s[3] += w[k] / total * dy * dy;
  }
  s[2] = s[1];
  return s;
}

// The documented regularisation's ridge for WideSpace: (1e-6 x prior sd 100)^2 on the diagonal.
Mat2 WithRidge(Mat2 s) {
  s[0] += 1e-8;
  s[3] += 1e-8;
  return s;
}

const std::vector<Vec2> kEvalPoints = {
    {0.0, 0.0}, {1.0, 2.0}, {-0.7, 0.4}, {2.5, -1.0}, {0.3, 0.31}, {4.0, 4.0}};
constexpr double kLogTol = 1e-10;

TEST(NormalKernel, LogDensityMatchesTheHandComputedMixture) {
  // Three particles in 2-D (full-rank covariance), unequal weights, scale 2 (Beaumont et al.).
  const std::vector<Vec2> r = {{0.0, 0.0}, {1.0, 0.5}, {0.2, 1.5}};
  const std::vector<double> w = {0.5, 0.3, 0.2};
  const ParameterSpace space = WideSpace();
  const auto proposal = MakeNormalKernel(2.0)->Fit(MakePopulation(r, w), space);
  Mat2 s = WeightedCovariance(r, w, nullptr);
  for (double& v : s) v *= 2.0;
  s = WithRidge(s);
  for (const Vec2& x : kEvalPoints) {
    EXPECT_NEAR(proposal->LogDensity(x), LogMixture(x, r, w, {s, s, s}), kLogTol)
        << x[0] << ", " << x[1];
  }
  // Weights need not arrive normalised; the kernel normalises them.
  const auto doubled = MakeNormalKernel(2.0)->Fit(MakePopulation(r, {1.0, 0.6, 0.4}), space);
  EXPECT_NEAR(doubled->LogDensity(kEvalPoints[1]), proposal->LogDensity(kEvalPoints[1]), 1e-12);
}

TEST(NormalKernel, TwoParticlesAgreeingInOneCoordinateUseThePriorScaleThere) {
  // Two particles in 2-D that share y: the y variance is 0, so (documented rule) the y kernel sd
  // is 0.1 x the prior sd of y, and every diagonal entry gains (1e-6 tau)^2.
  const std::vector<Vec2> r = {{0.0, 0.5}, {1.0, 0.5}};
  const std::vector<double> w = {0.25, 0.75};
  const ParameterSpace space = Space2(Normal(0.0, 3.0), Uniform(0.0, 2.0));
  const double tau_x = 3.0, tau_y = 2.0 / std::sqrt(12.0);
  const auto proposal = MakeNormalKernel(2.0)->Fit(MakePopulation(r, w), space);
  const double var_x = 2.0 * 0.25 * 0.75 + 1e-12 * tau_x * tau_x;
  const double var_y = 0.01 * tau_y * tau_y + 1e-12 * tau_y * tau_y;
  const Mat2 s = {var_x, 0.0, 0.0, var_y};
  for (const Vec2& x : {Vec2{0.1, 0.5}, Vec2{0.9, 0.6}, Vec2{-1.0, 0.01}}) {
    EXPECT_NEAR(proposal->LogDensity(x), LogMixture(x, r, w, {s, s}), 1e-10);
  }
}

TEST(NormalKernel, SingleParticleGetsATenthOfThePriorSdInEveryCoordinate) {
  const ParameterSpace space = Space2(Normal(0.0, 3.0), Normal(5.0, 0.5));
  const Vec2 c = {1.0, 5.2};
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto proposal = kernel->Fit(MakePopulation({c}, {1.0}), space);
    const Mat2 s = {(0.01 + 1e-12) * 9.0, 0.0, 0.0, (0.01 + 1e-12) * 0.25};
    for (const Vec2& x : {Vec2{1.0, 5.2}, Vec2{1.3, 5.1}, Vec2{0.0, 5.3}}) {
      EXPECT_NEAR(proposal->LogDensity(x), LogNormal2(x, c, s), 1e-10) << kernel->name();
    }
    RandomStream rng(3, 0, 0);
    std::vector<double> draw(2);
    double sum_sq = 0.0;
    constexpr int kDraws = 20000;
    for (int i = 0; i < kDraws; ++i) {
      proposal->Sample(rng, draw);
      sum_sq += (draw[0] - c[0]) * (draw[0] - c[0]);
    }
    // The x kernel variance is 0.09: the mean square is within 6 SE (sqrt(2/n) relative) of it.
    EXPECT_NEAR(sum_sq / kDraws, 0.09, 6.0 * 0.09 * std::sqrt(2.0 / kDraws)) << kernel->name();
  }
}

TEST(OlcmKernel, LocalCovariancesFollowTheDefinition) {
  // Four particles; three within the next thresholds. Each component's covariance is
  // sum_k w~_k (r_k - r_j)(r_k - r_j)^T over those three, w~ their weights renormalised; the
  // fourth particle is a centre but does not shape any covariance.
  const std::vector<Vec2> r = {{0.0, 0.0}, {1.0, 0.5}, {0.2, 1.5}, {2.0, 2.0}};
  const std::vector<double> w = {0.4, 0.3, 0.2, 0.1};
  const std::vector<std::uint8_t> within = {1, 1, 1, 0};
  const ParameterSpace space = WideSpace();
  const auto proposal = MakeOlcmKernel()->Fit(MakePopulation(r, w, within), space);
  std::vector<Mat2> s;
  for (std::size_t j = 0; j < r.size(); ++j) {
    s.push_back(WithRidge(OlcmCovariance(r, w, within, j)));
  }
  for (const Vec2& x : kEvalPoints) {
    EXPECT_NEAR(proposal->LogDensity(x), LogMixture(x, r, w, s), kLogTol) << x[0] << ", " << x[1];
  }
  // None within the next thresholds (or none marked): all particles shape the covariances.
  const std::vector<std::uint8_t> all = {1, 1, 1, 1};
  const auto all_marked = MakeOlcmKernel()->Fit(MakePopulation(r, w, all), space);
  for (const auto& unmarked :
       {std::vector<std::uint8_t>{0, 0, 0, 0}, std::vector<std::uint8_t>{}}) {
    const auto fallback = MakeOlcmKernel()->Fit(MakePopulation(r, w, unmarked), space);
    for (const Vec2& x : kEvalPoints) {
      EXPECT_NEAR(fallback->LogDensity(x), all_marked->LogDensity(x), 1e-12);
    }
  }
  EXPECT_GT(std::abs(all_marked->LogDensity(kEvalPoints[1]) - proposal->LogDensity(kEvalPoints[1])),
            1e-3);
}

// Sample mean and covariance of `draws` (n x 2) against the mixture's, each entry within 6 of its
// standard errors (estimated from the draws): a false failure has probability ~1e-8 per entry.
void ExpectMoments(const std::vector<Vec2>& draws, const Vec2& mean, const Mat2& cov) {
  const auto n = static_cast<double>(draws.size());
  Vec2 m{0.0, 0.0};
  for (const Vec2& x : draws) {
    m[0] += x[0] / n;
    m[1] += x[1] / n;
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(m[i], mean[i], 6.0 * std::sqrt(cov[static_cast<std::size_t>(3 * i)] / n))
        << "mean " << i;
  }
  for (auto [a, b] : {std::pair{0, 0}, std::pair{0, 1}, std::pair{1, 1}}) {
    double s = 0.0, s2 = 0.0;
    for (const Vec2& x : draws) {
      const double p = (x[a] - mean[a]) * (x[b] - mean[b]);
      s += p / n;
      s2 += p * p / n;
    }
    EXPECT_NEAR(s, cov[2 * a + b], 6.0 * std::sqrt((s2 - s * s) / n)) << "cov " << a << b;
  }
}

TEST(ContinuousKernels, SamplesHaveTheMixturesMeanAndCovariance) {
  // Mixture moments: mean = sum_j w_j c_j, covariance = sum_j w_j (Sigma_j + c_j c_j^T) - mean
  // mean^T. For the normal kernel with shared Sigma = s C this is (1 + s) C.
  const std::vector<Vec2> r = {{0.0, 0.0}, {1.0, 0.5}, {0.2, 1.5}, {2.0, 2.0}};
  const std::vector<double> w = {0.4, 0.3, 0.2, 0.1};
  const std::vector<std::uint8_t> within = {1, 1, 1, 0};
  const ParameterSpace space = WideSpace();
  constexpr int kDraws = 100000;
  Vec2 mean;
  const Mat2 c = WeightedCovariance(r, w, &mean);

  const auto normal = MakeNormalKernel(2.0)->Fit(MakePopulation(r, w), space);
  std::vector<Vec2> draws(kDraws);
  RandomStream rng(11, 0, 0);
  for (Vec2& x : draws) normal->Sample(rng, x);
  ExpectMoments(draws, mean, {3.0 * c[0], 3.0 * c[1], 3.0 * c[2], 3.0 * c[3]});

  const auto olcm = MakeOlcmKernel()->Fit(MakePopulation(r, w, within), space);
  Mat2 olcm_cov = {-mean[0] * mean[0], -mean[0] * mean[1], -mean[0] * mean[1], -mean[1] * mean[1]};
  for (std::size_t j = 0; j < r.size(); ++j) {
    const Mat2 s = OlcmCovariance(r, w, within, j);
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) olcm_cov[2 * a + b] += w[j] * (s[2 * a + b] + r[j][a] * r[j][b]);
    }
  }
  for (Vec2& x : draws) olcm->Sample(rng, x);
  ExpectMoments(draws, mean, olcm_cov);
}

TEST(ContinuousKernels, ThreeDimensionsMatchADenseComputation) {
  // d = 3 exercises the packed triangular factors beyond 2 x 2: densities against Eigen's dense
  // inverse and determinant, and samples of the normal kernel against its covariance (1 + 2) C.
  const int n = 5;
  Eigen::MatrixXd r(n, 3);
  r << 0.1, 0.2, -0.3, 1.0, 0.4, 0.2, -0.5, 1.1, 0.9, 0.3, -0.8, 1.4, 0.7, 0.6, -0.1;
  const Eigen::VectorXd w = (Eigen::VectorXd(n) << 0.1, 0.3, 0.2, 0.25, 0.15).finished();
  const std::vector<std::uint8_t> within = {0, 1, 1, 1, 1};
  const ParameterSpace space(
      BinarySpace::Independent(1),
      {{"a", Normal(0.0, 100.0)}, {"b", Normal(0.0, 100.0)}, {"c", Normal(0.0, 100.0)}});
  Population population;
  population.size = n;
  population.num_reals = 3;
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k < 3; ++k) population.reals.push_back(r(j, k));
    population.weights.push_back(w(j));
  }
  population.within_next = within;
  const Eigen::RowVectorXd mean = w.transpose() * r;
  const Eigen::MatrixXd centred = r.rowwise() - mean;
  const Eigen::MatrixXd c = centred.transpose() * w.asDiagonal() * centred;
  const Eigen::MatrixXd ridge = 1e-8 * Eigen::MatrixXd::Identity(3, 3);
  std::vector<Eigen::MatrixXd> olcm;
  for (int j = 0; j < n; ++j) {
    Eigen::MatrixXd s = ridge;
    double total = 0.0;
    for (int k = 0; k < n; ++k) total += within[k] ? w(k) : 0.0;
    for (int k = 0; k < n; ++k) {
      if (!within[k]) continue;
      const Eigen::RowVectorXd dr = r.row(k) - r.row(j);
      s += w(k) / total * dr.transpose() * dr;
    }
    olcm.push_back(s);
  }
  auto log_mixture = [&](const Eigen::VectorXd& x, bool local) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j) {
      const Eigen::MatrixXd s = local ? olcm[j] : Eigen::MatrixXd(2.0 * c + ridge);
      const Eigen::VectorXd dx = x - r.row(j).transpose();
      const double q = dx.dot(s.inverse() * dx);
      sum +=
          w(j) * std::exp(-1.5 * std::log(2.0 * M_PI) - 0.5 * std::log(s.determinant()) - 0.5 * q);
    }
    return std::log(sum);
  };
  const auto normal = MakeNormalKernel(2.0)->Fit(population, space);
  const auto local = MakeOlcmKernel()->Fit(population, space);
  for (const auto& x : {Eigen::Vector3d(0.0, 0.0, 0.0),
                        Eigen::Vector3d(0.3, 0.9, 0.1),
                        Eigen::Vector3d(-1.0, 2.0, 1.0)}) {
    const std::vector<double> v(x.data(), x.data() + 3);
    EXPECT_NEAR(normal->LogDensity(v), log_mixture(x, false), kLogTol);
    EXPECT_NEAR(local->LogDensity(v), log_mixture(x, true), kLogTol);
  }
  constexpr int kDraws = 100000;
  RandomStream rng(12, 0, 0);
  std::vector<double> v(3);
  Eigen::MatrixXd draws(kDraws, 3);
  for (int i = 0; i < kDraws; ++i) {
    normal->Sample(rng, v);
    draws.row(i) << v[0], v[1], v[2];
  }
  const Eigen::MatrixXd expected = 3.0 * c;
  const Eigen::MatrixXd d = draws.rowwise() - mean;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(d.col(a).mean(), 0.0, 6.0 * std::sqrt(expected(a, a) / kDraws)) << a;
    for (int b = a; b < 3; ++b) {
      const Eigen::ArrayXd p = d.col(a).array() * d.col(b).array();
      const double se = std::sqrt((p.square().mean() - p.mean() * p.mean()) / kDraws);
      EXPECT_NEAR(p.mean(), expected(a, b), 6.0 * se) << a << b;
    }
  }
}

TEST(ContinuousKernels, SamplesStayInsideTheSupportAtItsEdges) {
  // Uniform priors on [0, 1]^2 with particles on the edges and corners: about half of each
  // kernel's mass lies outside, and Sample must draw again until it lands inside.
  const ParameterSpace space = Space2(Uniform(0.0, 1.0), Uniform(0.0, 1.0));
  const std::vector<Vec2> r = {{0.0, 0.0}, {1.0, 0.5}, {0.5, 1.0}, {1.0, 1.0}, {0.0, 0.7}};
  const std::vector<double> w = {0.3, 0.2, 0.2, 0.2, 0.1};
  const std::vector<std::uint8_t> within = {1, 0, 1, 1, 0};
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto proposal = kernel->Fit(MakePopulation(r, w, within), space);
    RandomStream rng(5, 1, 0);
    std::vector<double> x(2);
    int near_edge = 0;
    for (int i = 0; i < 20000; ++i) {
      proposal->Sample(rng, x);
      ASSERT_TRUE(x[0] >= 0.0 && x[0] <= 1.0 && x[1] >= 0.0 && x[1] <= 1.0)
          << kernel->name() << ": " << x[0] << ", " << x[1];
      ASSERT_TRUE(std::isfinite(proposal->LogDensity(x)));
      near_edge += x[0] < 0.05 || x[0] > 0.95;
    }
    EXPECT_GT(near_edge, 1000) << kernel->name();  // the edges are reached, not avoided
    const std::vector<double> outside = {1.01, 0.5};
    EXPECT_EQ(proposal->LogDensity(outside), -INFINITY);
  }
}

TEST(ContinuousKernels, AKernelFarWiderThanTheBoxStillDrawsInsideIt) {
  // scale = 1e12 spreads the kernel over ~1e6 x the unit square along the particles' line: ~1e-12
  // of its mass is inside, which defeated rejection (10000 draws in a row outside). Each
  // coordinate drawn from its truncated conditional lands inside at once: x nearly uniform, y
  // close to the line through the particles.
  const ParameterSpace space = Space2(Uniform(0.0, 1.0), Uniform(0.0, 1.0));
  const auto proposal =
      MakeNormalKernel(1e12)->Fit(MakePopulation({{0.2, 0.2}, {0.8, 0.7}}, {0.5, 0.5}), space);
  RandomStream rng(1, 1, 1);
  std::vector<double> x(2);
  double mean = 0.0;
  for (int i = 0; i < 2000; ++i) {
    proposal->Sample(rng, x);
    ASSERT_TRUE(space.InSupport(x)) << x[0] << ", " << x[1];
    ASSERT_TRUE(std::isfinite(proposal->LogDensity(x))) << x[0] << ", " << x[1];
    mean += x[0] / 2000.0;
  }
  EXPECT_NEAR(mean, 0.5, 6.0 * std::sqrt(1.0 / 12.0 / 2000.0));
}

// Integral of exp(LogDensity) over [0, 1]^2 and the first moments, by the midpoint rule.
struct BoxIntegral {
  double mass = 0.0, m0 = 0.0, m1 = 0.0;
};
BoxIntegral Integrate(const ContinuousProposal& q) {
  constexpr int kSteps = 150;
  constexpr double h = 1.0 / kSteps;
  BoxIntegral out;
  std::vector<double> x(2);
  for (int i = 0; i < kSteps; ++i) {
    for (int k = 0; k < kSteps; ++k) {
      x = {(i + 0.5) * h, (k + 0.5) * h};
      const double p = std::exp(q.LogDensity(x)) * h * h;
      out.mass += p;
      out.m0 += p * x[0];
      out.m1 += p * x[1];
    }
  }
  return out;
}

// The draws' means against the density's, normalised by its integral over the unit box: the
// density is what Sample draws from, up to the constant it is documented to leave out.
void ExpectDrawsFollowTheDensity(const ContinuousProposal& q, const BoxIntegral& exact) {
  RandomStream rng(21, 0, 0);
  constexpr int kDraws = 10000;
  std::vector<double> x(2);
  double m0 = 0.0, m1 = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    q.Sample(rng, x);
    ASSERT_TRUE(x[0] >= 0.0 && x[0] <= 1.0 && x[1] >= 0.0 && x[1] <= 1.0);
    m0 += x[0] / kDraws;
    m1 += x[1] / kDraws;
  }
  // sd <= 0.5 on the unit box: 6 standard errors of a mean are at most 0.03.
  EXPECT_NEAR(m0, exact.m0 / exact.mass, 6.0 * 0.5 / std::sqrt(kDraws));
  EXPECT_NEAR(m1, exact.m1 / exact.mass, 6.0 * 0.5 / std::sqrt(kDraws));
}

TEST(ContinuousKernels, KernelsThatRarelyLandInsideAreTruncatedAndNormalisedOnTheBox) {
  // Particles spread far beyond the unit box (as a population can be, relative to a narrow box):
  // well under 2% of the untruncated mixture lands inside, so each Gaussian is truncated to the
  // box coordinate by coordinate. Each is normalised there, so the density integrates to 1 (no
  // constant left out), and its moments are the draws'.
  const ParameterSpace space = Space2(Uniform(0.0, 1.0), Uniform(0.0, 1.0));
  const std::vector<Vec2> r = {{-6.0, 4.0}, {5.0, 7.0}, {0.5, -8.0}, {9.0, -3.0}, {0.3, 0.6}};
  const std::vector<double> w = {0.3, 0.2, 0.2, 0.2, 0.1};
  const std::vector<std::uint8_t> within = {1, 0, 1, 1, 1};
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto q = kernel->Fit(MakePopulation(r, w, within), space);
    const BoxIntegral exact = Integrate(*q);
    EXPECT_NEAR(exact.mass, 1.0, 1e-4) << kernel->name();
    ExpectDrawsFollowTheDensity(*q, exact);
  }
}

TEST(ContinuousKernels, KernelsThatOftenLandInsideRedrawWholeAndOmitOneConstant) {
  // Correlated particles near the edges and corners of [0, 1]^2: a good share of the mixture is
  // inside, so a draw outside is redrawn whole, and the density is the mixture's on the box, its
  // mass there (between 0 and 1) the constant common to the wave.
  const ParameterSpace space = Space2(Uniform(0.0, 1.0), Uniform(0.0, 1.0));
  const std::vector<Vec2> r = {{0.05, 0.1}, {0.9, 0.8}, {0.5, 0.95}, {0.98, 0.97}, {0.3, 0.35}};
  const std::vector<double> w = {0.3, 0.2, 0.2, 0.2, 0.1};
  const std::vector<std::uint8_t> within = {1, 0, 1, 1, 0};
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto q = kernel->Fit(MakePopulation(r, w, within), space);
    const BoxIntegral exact = Integrate(*q);
    EXPECT_GT(exact.mass, 0.1) << kernel->name();
    EXPECT_LT(exact.mass, 0.9) << kernel->name();
    ExpectDrawsFollowTheDensity(*q, exact);
  }
}

TEST(ContinuousKernels, ThirtyBoundedRealsAreDrawnWithoutRejection) {
  // 30 uniform reals and a population spread over the whole box (wave 1's situation): each
  // Gaussian puts ~60% of its mass inside per coordinate, so a joint draw is inside with
  // probability ~1e-7 and rejection gave up. Truncating each coordinate never leaves the box.
  constexpr int kD = 30, kN = 100;
  std::vector<ContinuousParameter> reals;
  reals.reserve(kD);
  for (int k = 0; k < kD; ++k) reals.push_back({"r" + std::to_string(k), Uniform(-1.0, 1.0)});
  const ParameterSpace space(BinarySpace::Independent(0), reals);
  Population population;
  population.size = kN;
  population.num_reals = kD;
  RandomStream fill(3, 0, 0);
  for (int j = 0; j < kN; ++j) {
    for (int k = 0; k < kD; ++k) population.reals.push_back(2.0 * fill.Uniform() - 1.0);
    population.weights.push_back(1.0);
  }
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto q = kernel->Fit(population, space);
    RandomStream rng(4, 0, 0);
    std::vector<double> x(kD);
    for (int i = 0; i < 100; ++i) {
      q->Sample(rng, x);
      ASSERT_TRUE(space.InSupport(x)) << kernel->name();
      ASSERT_TRUE(std::isfinite(q->LogDensity(x))) << kernel->name();
    }
  }
}

TEST(ContinuousKernels, SameStreamSameDraws) {
  const std::vector<Vec2> r = {{0.0, 0.0}, {1.0, 0.5}, {0.2, 1.5}};
  const std::vector<double> w = {0.5, 0.3, 0.2};
  const ParameterSpace space = Space2(Uniform(-1.0, 2.0), Normal(0.0, 1.0));
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto a = kernel->Fit(MakePopulation(r, w, {1, 1, 0}), space);
    const auto b = kernel->Fit(MakePopulation(r, w, {1, 1, 0}), space);
    RandomStream ra(9, 2, 7), rb(9, 2, 7), rc(9, 2, 8);
    std::vector<double> xa(2), xb(2), xc(2);
    int differ = 0;
    for (int i = 0; i < 100; ++i) {
      a->Sample(ra, xa);
      b->Sample(rb, xb);
      a->Sample(rc, xc);
      ASSERT_EQ(xa, xb) << kernel->name();
      differ += xa != xc;
    }
    EXPECT_EQ(differ, 100) << kernel->name();
  }
}

TEST(ContinuousKernels, ZeroWeightParticlesAndEmptyPopulations) {
  const std::vector<Vec2> r = {{0.0, 0.0}, {1.0, 0.5}, {0.2, 1.5}};
  const std::vector<double> w = {0.5, 0.3, 0.2};
  const ParameterSpace space = WideSpace();
  std::vector<Vec2> r_extra = r;
  r_extra.push_back({50.0, -30.0});
  std::vector<double> w_extra = w;
  w_extra.push_back(0.0);
  for (const auto& kernel : {MakeNormalKernel(2.0), MakeOlcmKernel()}) {
    const auto base = kernel->Fit(MakePopulation(r, w, {1, 1, 0}), space);
    const auto extra = kernel->Fit(MakePopulation(r_extra, w_extra, {1, 1, 0, 1}), space);
    for (const Vec2& x : kEvalPoints) {
      EXPECT_NEAR(extra->LogDensity(x), base->LogDensity(x), 1e-10) << kernel->name();
    }
    // An empty population proposes from the prior.
    Population none;
    none.num_reals = 2;
    const auto empty = kernel->Fit(none, space);
    EXPECT_DOUBLE_EQ(empty->LogDensity(kEvalPoints[1]), space.LogPriorReals(kEvalPoints[1]));
  }
}

TEST(ContinuousKernels, FactoryAndNames) {
  ProposalOptions options;
  EXPECT_EQ(MakeContinuousKernel(options)->name(), "normal");
  options.continuous = ContinuousKernelKind::kOlcm;
  EXPECT_EQ(MakeContinuousKernel(options)->name(), "olcm");
  for (double bad : {0.0, -1.0, HUGE_VAL, std::nan("")}) {
    try {
      MakeNormalKernel(bad);
      FAIL() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kConfig);
      EXPECT_NE(e.message().find("ProposalOptions::scale"), std::string::npos);
    }
  }
}

// The base class's Prior, through a kernel that only has it.
class PriorOnlyKernel final : public ContinuousKernel {
 public:
  std::string name() const override { return "prior only"; }
  std::unique_ptr<ContinuousProposal> Fit(const Population&,
                                          const ParameterSpace& space) const override {
    return Prior(space);
  }
};

TEST(ContinuousKernelPrior, DrawsEachRealFromItsPriorInOrder) {
  const ParameterSpace space = Space2(
      Uniform(0.0, 1.0),
      {.kind = PriorKind::kTruncatedNormal, .low = 0.0, .high = 4.0, .mean = 1.0, .sd = 2.0});
  const auto proposal = PriorOnlyKernel().Prior(space);
  RandomStream rng(1, 2, 3), replay(1, 2, 3);
  std::vector<double> r(2);
  for (int i = 0; i < 1000; ++i) {
    proposal->Sample(rng, r);
    // Same stream, the priors in order: the same numbers.
    EXPECT_EQ(r[0], space.reals()[0].prior.Sample(replay));
    EXPECT_EQ(r[1], space.reals()[1].prior.Sample(replay));
    EXPECT_TRUE(space.InSupport(r));
    EXPECT_DOUBLE_EQ(proposal->LogDensity(r), space.LogPriorReals(r));
  }
  const std::vector<double> outside = {1.5, 1.0};
  EXPECT_EQ(proposal->LogDensity(outside), -INFINITY);
}

}  // namespace
}  // namespace combabc
