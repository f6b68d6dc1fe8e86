#include "combabc/params/continuous_prior.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "params/truncated_normal.hpp"

namespace combabc {
namespace {

ContinuousPrior Uniform(double low, double high) {
  return {.kind = PriorKind::kUniform, .low = low, .high = high};
}
ContinuousPrior Normal(double mean, double sd) {
  return {.kind = PriorKind::kNormal, .mean = mean, .sd = sd};
}
ContinuousPrior LogNormal(double mean, double sd) {
  return {.kind = PriorKind::kLogNormal, .mean = mean, .sd = sd};
}
ContinuousPrior Truncated(double mean, double sd, double low, double high) {
  return {.kind = PriorKind::kTruncatedNormal, .low = low, .high = high, .mean = mean, .sd = sd};
}

// Upper tail of N(0, 1), independent of the implementation's branches.
double Q(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

// Priors covering every kind and every branch of the truncated normal: central, one-sided,
// a far tail ([5, 6] sd), an interval narrower than its sd, a left tail, and an interval 6 sd
// from the mean where only ~1e-9 of the normal mass remains.
std::vector<ContinuousPrior> TestPriors() {
  return {Uniform(-1.0, 3.0),
          Uniform(1e6, 1e6 + 2.5),
          Normal(1.5, 2.0),
          LogNormal(0.3, 0.5),
          LogNormal(-2.0, 1.2),
          Truncated(0.0, 1.0, -1.0, 2.0),
          Truncated(1.0, 2.0, 1.0, 50.0),
          Truncated(0.0, 1.0, 5.0, 6.0),
          Truncated(0.0, 1.0, 0.3, 0.3 + 1e-4),
          Truncated(2.0, 0.5, -1.0, 0.5),
          Truncated(10.0, 1.0, 0.0, 4.0)};
}

std::string Describe(const ContinuousPrior& p) {
  return std::string(ToString(p.kind)) + " low=" + std::to_string(p.low) +
         " high=" + std::to_string(p.high) + " mean=" + std::to_string(p.mean) +
         " sd=" + std::to_string(p.sd);
}

// Composite Simpson's rule of f on [a, b] with n (even) panels.
double Simpson(const std::function<double(double)>& f, double a, double b, int n = 20000) {
  const double h = (b - a) / n;
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(a + i * h);
  return sum * h / 3.0;
}

// The k-th moment of x under p's density, by quadrature over where the mass is (lognormal: in
// t = log x, dx = x dt).
double Moment(const ContinuousPrior& p, int k) {
  auto pow_k = [k](double x) { return std::pow(x, k); };
  switch (p.kind) {
    case PriorKind::kUniform:
    case PriorKind::kTruncatedNormal:
      return Simpson([&](double x) { return pow_k(x) * std::exp(p.LogDensity(x)); }, p.low, p.high);
    case PriorKind::kNormal:
      return Simpson([&](double x) { return pow_k(x) * std::exp(p.LogDensity(x)); },
                     p.mean - 14 * p.sd,
                     p.mean + 14 * p.sd);
    case PriorKind::kLogNormal:
      return Simpson(
          [&](double t) {
            const double x = std::exp(t);
            return pow_k(x) * std::exp(p.LogDensity(x)) * x;
          },
          p.mean - 14 * p.sd,
          p.mean + 14 * p.sd);
    case PriorKind::kJoint:  // no density of its own (joint_prior_test.cpp)
      break;
  }
  return NAN;
}

TEST(ContinuousPrior, TestPriorsAreValid) {
  for (const auto& p : TestPriors()) {
    std::string why;
    EXPECT_TRUE(p.IsValid(&why)) << Describe(p) << ": " << why;
  }
}

TEST(ContinuousPrior, DensityIntegratesToOneAndClosedFormMomentsMatchQuadrature) {
  // Simpson with 2e4 panels over each support: error far below the tolerances.
  constexpr double kMassTol = 1e-7;
  constexpr double kMomentRelTol = 1e-7;
  for (const auto& p : TestPriors()) {
    const double mass = Moment(p, 0);
    EXPECT_NEAR(mass, 1.0, kMassTol) << Describe(p);
    const double mean = Moment(p, 1) / mass;
    const double var = Moment(p, 2) / mass - mean * mean;
    // Uniform(1e6, ...): E[x^2] - E[x]^2 cancels 12 digits; skip its variance check.
    const double scale = std::abs(mean) + p.StandardDeviation();
    EXPECT_NEAR(p.Mean(), mean, kMomentRelTol * scale) << Describe(p);
    if (std::abs(mean) < 1e3) {
      EXPECT_NEAR(p.StandardDeviation(), std::sqrt(var), 1e-6 * p.StandardDeviation())
          << Describe(p);
    }
  }
}

TEST(ContinuousPrior, LogDensityKnownValues) {
  constexpr double kTol = 1e-12;
  const double log_sqrt_2pi = 0.5 * std::log(2.0 * M_PI);
  EXPECT_NEAR(Uniform(-1.0, 3.0).LogDensity(0.5), -std::log(4.0), kTol);
  EXPECT_NEAR(Normal(1.5, 2.0).LogDensity(3.5), -0.5 - std::log(2.0) - log_sqrt_2pi, kTol);
  // Lognormal at x = e^mean: the normal's peak in log x, times the Jacobian 1 / x.
  EXPECT_NEAR(
      LogNormal(0.3, 0.5).LogDensity(std::exp(0.3)), -std::log(0.5) - log_sqrt_2pi - 0.3, kTol);
  // N(0, 1) on [5, 6]: Z = Q(5) - Q(6) = 2.866515718791939e-7 - 9.865876450377e-10 (tables of the
  // normal tail). A normaliser computed as Phi(6) - Phi(5) would lose 9 of its 16 digits here.
  const double z = 2.866515718791939e-7 - 9.865876450376981e-10;
  EXPECT_NEAR(Truncated(0.0, 1.0, 5.0, 6.0).LogDensity(5.5),
              -0.5 * 5.5 * 5.5 - log_sqrt_2pi - std::log(z),
              1e-10);
  // Outside the support: -inf (and NaN is never in the support).
  EXPECT_EQ(Uniform(-1.0, 3.0).LogDensity(3.0000001), -INFINITY);
  EXPECT_EQ(LogNormal(0.0, 1.0).LogDensity(0.0), -INFINITY);
  EXPECT_EQ(LogNormal(0.0, 1.0).LogDensity(-1.0), -INFINITY);
  EXPECT_EQ(Truncated(0.0, 1.0, 5.0, 6.0).LogDensity(4.999), -INFINITY);
  EXPECT_EQ(Normal(0.0, 1.0).LogDensity(NAN), -INFINITY);
  EXPECT_EQ(Normal(0.0, 1.0).LogDensity(INFINITY), -INFINITY);
  EXPECT_TRUE(Uniform(-1.0, 3.0).InSupport(-1.0));  // closed interval
  EXPECT_TRUE(Uniform(-1.0, 3.0).InSupport(3.0));
  EXPECT_FALSE(Uniform(-1.0, 3.0).InSupport(NAN));
}

TEST(ContinuousPrior, SampleMomentsMatchMeanAndStandardDeviation) {
  // 1e5 draws from one fixed stream per prior. The sample mean is within 6 standard errors of
  // Mean(); the sample variance within 6 of its own standard errors (from the sample's fourth
  // central moment) of StandardDeviation()^2. Both bounds fail with probability ~2e-9.
  constexpr int kDraws = 100000;
  int index = 0;
  for (const auto& p : TestPriors()) {
    RandomStream rng(20260101, 3, static_cast<std::uint64_t>(index++));
    std::vector<double> x(kDraws);
    for (double& v : x) {
      v = p.Sample(rng);
      ASSERT_TRUE(p.InSupport(v)) << Describe(p) << " drew " << v;
    }
    double mean = 0.0;
    for (double v : x) mean += v;
    mean /= kDraws;
    double m2 = 0.0, m4 = 0.0;
    for (double v : x) {
      const double d = (v - mean) * (v - mean);
      m2 += d;
      m4 += d * d;
    }
    m2 /= kDraws;
    m4 /= kDraws;
    const double sd = p.StandardDeviation();
    EXPECT_NEAR(mean, p.Mean(), 6.0 * sd / std::sqrt(kDraws)) << Describe(p);
    EXPECT_NEAR(m2, sd * sd, 6.0 * std::sqrt((m4 - m2 * m2) / kDraws)) << Describe(p);
  }
}

// How many 64-bit outputs `after` has consumed since `before` (at most `limit`; -1 if more).
int Consumed(const RandomStream& before, const RandomStream& after, int limit) {
  RandomStream target = after;
  const std::uint64_t key[3] = {target.Next(), target.Next(), target.Next()};
  RandomStream probe = before;
  for (int k = 0; k <= limit; ++k) {
    RandomStream look = probe;
    if (look.Next() == key[0] && look.Next() == key[1] && look.Next() == key[2]) return k;
    probe.Next();
  }
  return -1;
}

TEST(ContinuousPrior, TruncatedNormalFarInATailIsExactAndCheap) {
  // N(0, 1) on [5, 6] holds 2.9e-7 of the mass: plain rejection would need ~3.5e6 normals per draw.
  // The exponential sampler (Robert 1995) accepts ~96% of its tries at 2 uniforms each.
  const ContinuousPrior p = Truncated(0.0, 1.0, 5.0, 6.0);
  RandomStream rng(99, 0, 0);
  constexpr int kCostDraws = 2000;
  long total = 0;
  for (int i = 0; i < kCostDraws; ++i) {
    const RandomStream before = rng;
    p.Sample(rng);
    const int used = Consumed(before, rng, 1000);
    ASSERT_GE(used, 2);
    total += used;
  }
  EXPECT_LT(static_cast<double>(total) / kCostDraws, 3.0);  // 2 / 0.96 = 2.08 expected

  // Exactness: the empirical CDF at interior points is within 6 binomial standard errors of
  // F(x) = (Q(5) - Q(x)) / (Q(5) - Q(6)).
  constexpr int kDraws = 100000;
  std::vector<double> x(kDraws);
  for (double& v : x) v = p.Sample(rng);
  const double z = Q(5.0) - Q(6.0);
  for (double t : {5.02, 5.05, 5.1, 5.2, 5.4, 5.7}) {
    const double f = (Q(5.0) - Q(t)) / z;
    double below = 0;
    for (double v : x) below += v <= t;
    EXPECT_NEAR(below / kDraws, f, 6.0 * std::sqrt(f * (1 - f) / kDraws)) << "t = " << t;
  }
  // Mirror image: the left tail [-6, -5].
  const ContinuousPrior left = Truncated(0.0, 1.0, -6.0, -5.0);
  for (double t : {-5.4, -5.1}) {
    const double f = (Q(-t) - Q(6.0)) / z;  // P(x <= t) = P(-x >= -t)
    double below = 0;
    for (int i = 0; i < kDraws; ++i) below += left.Sample(rng) <= t;
    EXPECT_NEAR(below / kDraws, f, 6.0 * std::sqrt(f * (1 - f) / kDraws)) << "t = " << t;
  }
}

TEST(ContinuousPrior, SamplingIsDeterministicPerStream) {
  for (const auto& p : TestPriors()) {
    RandomStream a(5, 1, 2), b(5, 1, 2);
    for (int i = 0; i < 100; ++i) ASSERT_EQ(p.Sample(a), p.Sample(b)) << Describe(p);
  }
}

TEST(ContinuousPrior, IsValidNamesTheBadField) {
  struct Case {
    ContinuousPrior prior;
    std::string expected;  // a substring of `why`
    std::string field;     // the structured error's field
  };
  const std::vector<Case> cases = {
      {Uniform(2.0, 1.0), "low = 2 >= high = 1; low must be below high", "low"},
      {Uniform(1.0, 1.0), "low = 1 >= high = 1", "low"},
      {Uniform(NAN, 1.0), "low = nan; must be finite", "low"},
      {Uniform(0.0, INFINITY), "high = inf; must be finite", "high"},
      {Uniform(-1.7e308, 1.7e308), "high - low = inf", "high - low"},
      {Normal(0.0, -1.0), "sd = -1; must be > 0", "sd"},
      {Normal(0.0, 0.0), "sd = 0; must be > 0", "sd"},
      {Normal(NAN, 1.0), "mean = nan; must be finite", "mean"},
      {Normal(0.0, INFINITY), "sd = inf; must be finite", "sd"},
      {LogNormal(0.0, -0.5), "sd = -0.5; must be > 0", "sd"},
      {LogNormal(0.0, 30.0), "mean + sd^2 must be below 700", "sd"},
      {Truncated(0.0, 0.0, -1.0, 1.0), "sd = 0; must be > 0", "sd"},
      {Truncated(0.0, 1.0, 1.0, -1.0), "low = 1 >= high = -1", "low"},
      {Truncated(0.0, 1.0, -INFINITY, 1.0), "low = -inf; must be finite", "low"},
      {Truncated(0.0, 1.0, 8.0, 9.0), "on [low, high], must be >= 1e-12", "low"},
      {Truncated(0.0, 1.0, 0.0, 1e-13), "on [low, high], must be >= 1e-12", "low"},
  };
  for (const auto& c : cases) {
    std::string why;
    EXPECT_FALSE(c.prior.IsValid(&why)) << Describe(c.prior);
    EXPECT_NE(why.find(c.expected), std::string::npos) << "why = " << why;
    // The structured form: the field, no owner (the caller names the prior), the same sentence.
    ValidationError error;
    EXPECT_FALSE(c.prior.IsValid(&error));
    EXPECT_EQ(error.field, c.field) << why;
    EXPECT_EQ(error.owner, "");
    EXPECT_EQ(error.Message(), why);
  }
  // Fields a kind does not use are not checked: a normal ignores low/high.
  ContinuousPrior normal = Normal(0.0, 1.0);
  normal.low = 5.0;
  normal.high = -5.0;
  EXPECT_TRUE(normal.IsValid(static_cast<ValidationError*>(nullptr)));
  // Just above the mass floor is valid: N(0, 1) on [7, 8] has 1.28e-12.
  EXPECT_TRUE(Truncated(0.0, 1.0, 7.0, 8.0).IsValid(static_cast<ValidationError*>(nullptr)));
}

// log Q(x) for large x from the asymptotic series Q(x) = phi(x) / x (1 - 1/x^2 + 3/x^4 - 15/x^6
// + 105/x^8 - 945/x^10), independent of the implementation (error ~1e-14 relative at x = 40).
double LogUpperTailSeries(double x) {
  const double u = 1.0 / (x * x);
  const double series =
      1.0 - u * (1.0 - 3.0 * u * (1.0 - 5.0 * u * (1.0 - 7.0 * u * (1.0 - 9.0 * u))));
  return -0.5 * x * x - 0.5 * std::log(2.0 * M_PI) - std::log(x) + std::log(series);
}

TEST(TruncatedNormal, LogMassIsAccurateFromTheCentreToFarTails) {
  // Where erfc is representable, its differences; beyond (x > 37), the asymptotic series. The
  // kernels need the far tails: a conditional mean can sit many sd outside a real's bounds.
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{{-1.0, 2.0},
                                                                   {0.5, 0.7},
                                                                   {7.9, 8.6},
                                                                   {9.0, 9.2},
                                                                   {12.0, 30.0},
                                                                   {29.0, 31.0},
                                                                   {33.0, 36.0},
                                                                   {5.0, INFINITY},
                                                                   {-INFINITY, -20.0}}) {
    const double direct = std::log(Q(a) - Q(b));
    EXPECT_NEAR(LogStandardNormalMass(a, b), direct, 1e-11 * std::fabs(direct) + 1e-13)
        << a << ", " << b;
  }
  for (const double x : {40.0, 100.0, 1e4}) {
    EXPECT_NEAR(LogStandardNormalMass(x, INFINITY), LogUpperTailSeries(x), 1e-12 * x * x) << x;
    EXPECT_EQ(LogStandardNormalMass(-INFINITY, -x), LogStandardNormalMass(x, INFINITY));
    // [x, x + 0.5]: all but exp(-x / 2)-ish of the tail's mass.
    const double narrow = LogStandardNormalMass(x, x + 0.5);
    const double both = LogUpperTailSeries(x) +
                        std::log1p(-std::exp(LogUpperTailSeries(x + 0.5) - LogUpperTailSeries(x)));
    EXPECT_NEAR(narrow, both, 1e-12 * x * x) << x;
  }
  EXPECT_EQ(LogStandardNormalMass(1.0, 1.0), -INFINITY);
}

TEST(TruncatedNormal, FarTailDrawsHaveTheTailsMean) {
  // N(0, 1) on [40, inf): mean phi(40) / Q(40) = 1 / R(40) ~ 40.025, sd ~ 1/40.
  RandomStream rng(8, 0, 0);
  const double log_mass = LogStandardNormalMass(40.0, INFINITY);
  const double mean = std::exp(-800.0 - 0.5 * std::log(2.0 * M_PI) - log_mass);
  double sum = 0.0;
  constexpr int kDraws = 20000;
  for (int i = 0; i < kDraws; ++i) {
    const double z = SampleStandardTruncated(40.0, INFINITY, log_mass, rng);
    ASSERT_GE(z, 40.0);
    sum += z;
  }
  EXPECT_NEAR(sum / kDraws, mean, 6.0 * (1.0 / 40.0) / std::sqrt(kDraws));
}

}  // namespace
}  // namespace combabc
