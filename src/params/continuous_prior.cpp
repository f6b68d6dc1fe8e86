#include "combabc/params/continuous_prior.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>

#include "combabc/core/check.hpp"

namespace combabc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kLogSqrt2Pi = 0.91893853320467274178;  // log sqrt(2 pi)
// A truncated normal needs at least this much N(mean, sd^2) mass on [low, high]: below it the
// normaliser is not worth trusting and no sampler is efficient (ContinuousPrior::IsValid).
constexpr double kMinTruncatedMass = 1e-12;
// exp(x) overflows a double above ~709.78: a lognormal whose moments need exp(mean + sd^2) beyond
// this has no finite mean or variance in double precision.
constexpr double kMaxLogMoment = 700.0;
// Intervals narrower than this (in standard deviations) get their mass and moments by
// Gauss-Legendre quadrature instead of differences of erfc, which cancel when b is close to a.
constexpr double kNarrowWidth = 1.0;

// Shortest text that reads back as the same double ("-1", "0.1", "inf").
std::string Num(double x) {
  std::array<char, 32> buf{};
  const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return {buf.data(), result.ptr};
}

double StdNormalPdf(double z) { return std::exp(-0.5 * z * z - kLogSqrt2Pi); }

// 10-point Gauss-Legendre rule on [-1, 1] (Abramowitz & Stegun 1964, Table 25.4): exact for
// polynomials of degree 19. On an interval of width w <= 1 at |z| <= 8 the normal density's
// derivatives scale like 8^k, so the rule's error is below 1e-20 relative (A&S 25.4.30).
constexpr std::array<double, 5> kGaussNodes = {0.1488743389816312,
                                               0.4333953941292472,
                                               0.6794095682990244,
                                               0.8650633666889845,
                                               0.9739065285171717};
constexpr std::array<double, 5> kGaussWeights = {0.2955242247147529,
                                                 0.2692667193099963,
                                                 0.2190863625159820,
                                                 0.1494513491505806,
                                                 0.0666713443086881};

// N(0, 1) restricted to [a, b] in standard units: its mass Z = Phi(b) - Phi(a), and its mean and
// variance (Johnson, Kotz & Balakrishnan 1994, Sec. 10.1).
struct StandardTruncation {
  double a = 0.0, b = 0.0;
  double mass = 0.0;
  double mean = 0.0;
  double variance = 0.0;
};

StandardTruncation Truncate(double a, double b) {
  StandardTruncation t{a, b};
  if (b - a <= kNarrowWidth) {
    // Narrow: Z = Phi(b) - Phi(a) would cancel. Integrate phi, (z - m) phi and (z - m)^2 phi about
    // the midpoint m instead; each term is positive or small, so the result is accurate to a few
    // ulps however narrow the interval.
    const double m = 0.5 * (a + b), h = 0.5 * (b - a);
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (std::size_t i = 0; i < kGaussNodes.size(); ++i) {
      for (const double sign : {-1.0, 1.0}) {
        const double u = sign * h * kGaussNodes[i];
        const double f = kGaussWeights[i] * StdNormalPdf(m + u);
        s0 += f;
        s1 += f * u;
        s2 += f * u * u;
      }
    }
    t.mass = h * s0;
    const double shift = s1 / s0;
    t.mean = m + shift;
    t.variance = std::max(s2 / s0 - shift * shift, 0.0);
    return t;
  }
  // Wide: Phi(b) - Phi(a) from the tail the interval lies in, via erfc, which keeps full relative
  // precision in both tails; b - a > 1 keeps the difference from cancelling by more than a factor
  // of ~3 there.
  const double r = std::numbers::sqrt2 / 2.0;  // 1 / sqrt(2)
  if (a >= 0.0) {
    t.mass = 0.5 * (std::erfc(a * r) - std::erfc(b * r));
  } else if (b <= 0.0) {
    t.mass = 0.5 * (std::erfc(-b * r) - std::erfc(-a * r));
  } else {
    t.mass = 1.0 - 0.5 * std::erfc(-a * r) - 0.5 * std::erfc(b * r);
  }
  const double pa = std::isfinite(a) ? StdNormalPdf(a) : 0.0;
  const double pb = std::isfinite(b) ? StdNormalPdf(b) : 0.0;
  const double apa = std::isfinite(a) ? a * pa : 0.0;
  const double bpb = std::isfinite(b) ? b * pb : 0.0;
  const double lambda = (pa - pb) / t.mass;
  t.mean = lambda;
  t.variance = std::max(1.0 + (apa - bpb) / t.mass - lambda * lambda, 0.0);
  return t;
}

StandardTruncation TruncateStandardised(const ContinuousPrior& p) {
  return Truncate((p.low - p.mean) / p.sd, (p.high - p.mean) / p.sd);
}

// One draw of N(0, 1) restricted to [a, b] (0 <= a < b, b may be +inf) by exponential rejection
// (Robert 1995, "Simulation of truncated normal variables", Stat. Comput. 5:121, Prop. 2.3): the
// proposal a + Exp(alpha) with the optimal rate alpha = (a + sqrt(a^2 + 4)) / 2, accepted with
// probability exp(-(z - alpha)^2 / 2); draws above b are rejected.
double SampleExponentialTail(double a, double b, double alpha, RandomStream& rng) {
  for (;;) {
    const double z = a - std::log1p(-rng.Uniform()) / alpha;  // Uniform() < 1: log1p finite
    const double u = rng.Uniform();
    if (z <= b && u < std::exp(-0.5 * (z - alpha) * (z - alpha))) return z;
  }
}

// Uniform rejection on [a, b] (Robert 1995, Prop. 2.2): the envelope is phi at the point m of
// [a, b] nearest 0, so z is accepted with probability exp((m^2 - z^2) / 2).
double SampleUniformRejection(double a, double b, RandomStream& rng) {
  const double m = std::clamp(0.0, a, b);
  for (;;) {
    const double z = a + (b - a) * rng.Uniform();
    const double u = rng.Uniform();
    if (u < std::exp(0.5 * (m * m - z * z))) return z;
  }
}

// Plain rejection from N(0, 1): efficient whenever [a, b] holds a good share of the mass.
double SampleNormalRejection(double a, double b, RandomStream& rng) {
  for (;;) {
    const double z = rng.Normal();
    if (z >= a && z <= b) return z;
  }
}

// N(0, 1) on [a, b]. Of the three exact rejection samplers above, uses the one with the highest
// acceptance rate for this interval (each has a closed form, so the choice is deterministic and the
// expected number of tries is at most about 2 for any interval; Robert 1995, Sec. 2):
//   normal rejection:       Z
//   uniform rejection:      Z / ((b - a) phi(m))
//   exponential (one tail): Z alpha sqrt(2 pi) exp(alpha a - alpha^2 / 2)   (a >= 0)
// A left tail (b <= 0) is the mirror image of a right one.
double SampleStandardTruncated(const StandardTruncation& t, RandomStream& rng) {
  const double a = t.a, b = t.b;
  const bool mirror = b <= 0.0;  // sample -z on [-b, -a]
  const double lo = mirror ? -b : a, hi = mirror ? -a : b;
  const double log_z = std::log(t.mass);
  const double log_normal_rate = log_z;
  const double m = std::clamp(0.0, lo, hi);
  const double log_uniform_rate = log_z - std::log(hi - lo) + 0.5 * m * m + kLogSqrt2Pi;
  double log_exponential_rate = -kInf, alpha = 0.0;
  if (lo >= 0.0) {
    alpha = 0.5 * (lo + std::sqrt(lo * lo + 4.0));
    log_exponential_rate = log_z + std::log(alpha) + kLogSqrt2Pi + alpha * lo - 0.5 * alpha * alpha;
  }
  double z = 0.0;
  if (log_exponential_rate >= log_uniform_rate && log_exponential_rate >= log_normal_rate) {
    z = SampleExponentialTail(lo, hi, alpha, rng);
  } else if (log_uniform_rate >= log_normal_rate) {
    z = SampleUniformRejection(lo, hi, rng);
  } else {
    z = SampleNormalRejection(lo, hi, rng);
  }
  return mirror ? -z : z;
}

}  // namespace

bool ContinuousPrior::IsValid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  auto finite = [&](const char* field, double value) {
    return std::isfinite(value)
               ? true
               : fail(std::string(field) + " = " + Num(value) + "; must be finite");
  };
  if (kind == PriorKind::kJoint) {
    if (!(low < high)) {
      return fail("low = " + Num(low) + " >= high = " + Num(high) + "; low must be below high");
    }
    if (!finite("mean", mean) || !finite("sd", sd)) return false;
    return sd > 0.0 ? true : fail("sd = " + Num(sd) + "; must be > 0");
  }
  const bool uses_bounds = kind == PriorKind::kUniform || kind == PriorKind::kTruncatedNormal;
  const bool uses_normal = kind != PriorKind::kUniform;
  if (uses_bounds) {
    if (!finite("low", low) || !finite("high", high)) return false;
    if (!(low < high)) {
      return fail("low = " + Num(low) + " >= high = " + Num(high) + "; low must be below high");
    }
    if (!std::isfinite(high - low)) {
      return fail("high - low = " + Num(high - low) + "; the interval must have a finite width");
    }
  }
  if (uses_normal) {
    if (!finite("mean", mean) || !finite("sd", sd)) return false;
    if (!(sd > 0.0)) return fail("sd = " + Num(sd) + "; must be > 0");
  }
  switch (kind) {
    case PriorKind::kUniform:
    case PriorKind::kNormal:
    case PriorKind::kJoint:
      return true;
    case PriorKind::kLogNormal:
      if (mean + sd * sd >= kMaxLogMoment) {
        return fail("sd = " + Num(sd) + " with mean = " + Num(mean) +
                    "; mean + sd^2 must be below " + Num(kMaxLogMoment) +
                    " for the lognormal's mean and variance to be finite");
      }
      return true;
    case PriorKind::kTruncatedNormal: {
      const double mass = TruncateStandardised(*this).mass;
      if (!(mass >= kMinTruncatedMass)) {
        return fail("low = " + Num(low) + ", high = " + Num(high) + "; N(mean = " + Num(mean) +
                    ", sd = " + Num(sd) + ") has mass " + Num(mass) +
                    " on [low, high], must be >= " + Num(kMinTruncatedMass));
      }
      return true;
    }
  }
  return fail("kind = " + std::to_string(static_cast<int>(kind)) + "; not a prior kind");
}

bool ContinuousPrior::InSupport(double x) const {
  switch (kind) {
    case PriorKind::kUniform:
    case PriorKind::kTruncatedNormal:
      return x >= low && x <= high;  // false for NaN
    case PriorKind::kNormal:
      return std::isfinite(x);
    case PriorKind::kLogNormal:
      return x > 0.0 && x < kInf;
    case PriorKind::kJoint:
      return x >= low && x <= high && std::isfinite(x);
  }
  return false;
}

double ContinuousPrior::LogDensity(double x) const {
  if (!InSupport(x)) return -kInf;
  switch (kind) {
    case PriorKind::kUniform:
      return -std::log(high - low);
    case PriorKind::kNormal: {
      const double z = (x - mean) / sd;
      return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi;
    }
    case PriorKind::kLogNormal: {
      const double log_x = std::log(x);
      const double z = (log_x - mean) / sd;
      return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi - log_x;
    }
    case PriorKind::kTruncatedNormal: {
      const double z = (x - mean) / sd;
      return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi - std::log(TruncateStandardised(*this).mass);
    }
    case PriorKind::kJoint:
      COMBABC_CHECK(kind != PriorKind::kJoint);  // ParameterSpace::LogPriorReals
  }
  return -kInf;
}

double ContinuousPrior::Sample(RandomStream& rng) const {
  switch (kind) {
    case PriorKind::kUniform:
      // Uniform() < 1, but low + w u may round up to high, which the closed support allows.
      return low + (high - low) * rng.Uniform();
    case PriorKind::kNormal:
      return mean + sd * rng.Normal();
    case PriorKind::kLogNormal:
      for (;;) {
        // exp under- or overflows only beyond ~37 sd for a valid prior; such a draw is not in
        // the (open) support, so draw again rather than return 0 or inf.
        const double x = std::exp(mean + sd * rng.Normal());
        if (x > 0.0 && x < kInf) return x;
      }
    case PriorKind::kTruncatedNormal: {
      const double z = SampleStandardTruncated(TruncateStandardised(*this), rng);
      // z lies in [a, b]; mean + sd z may round a hair outside [low, high].
      return std::clamp(mean + sd * z, low, high);
    }
    case PriorKind::kJoint:
      COMBABC_CHECK(kind != PriorKind::kJoint);  // ParameterSpace::SampleReals
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double ContinuousPrior::Mean() const {
  switch (kind) {
    case PriorKind::kUniform:
      return 0.5 * (low + high);
    case PriorKind::kNormal:
    case PriorKind::kJoint:
      return mean;
    case PriorKind::kLogNormal:
      return std::exp(mean + 0.5 * sd * sd);
    case PriorKind::kTruncatedNormal:
      return std::clamp(mean + sd * TruncateStandardised(*this).mean, low, high);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double ContinuousPrior::StandardDeviation() const {
  switch (kind) {
    case PriorKind::kUniform:
      return (high - low) / std::sqrt(12.0);
    case PriorKind::kNormal:
    case PriorKind::kJoint:
      return sd;
    case PriorKind::kLogNormal:
      // sqrt(exp(sd^2) - 1) exp(mean + sd^2 / 2); expm1 keeps small sd accurate.
      return std::sqrt(std::expm1(sd * sd)) * std::exp(mean + 0.5 * sd * sd);
    case PriorKind::kTruncatedNormal:
      return sd * std::sqrt(TruncateStandardised(*this).variance);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace combabc
