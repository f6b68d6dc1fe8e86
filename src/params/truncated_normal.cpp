#include "params/truncated_normal.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace combabc {
namespace {

constexpr double kTruncInf = std::numeric_limits<double>::infinity();
constexpr double kTruncLogSqrt2Pi = 0.91893853320467274178;  // log sqrt(2 pi)
// Intervals narrower than this (in standard deviations) get their mass and moments by
// Gauss-Legendre quadrature instead of differences of erfc, which cancel when b is close to a.
constexpr double kNarrowWidth = 1.0;
// From this distance to 0 on, an interval's log mass is computed from the Mills ratio: the
// quadrature below is exact only within 8 of 0, and erfc itself leaves the normal doubles near 37.
constexpr double kTailStart = 8.0;
// From here on the Mills ratio comes from its continued fraction rather than erfc.
constexpr double kDeepTail = 30.0;

double StdNormalPdf(double z) { return std::exp(-0.5 * z * z - kTruncLogSqrt2Pi); }

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

// Mills ratio R(x) = Q(x) / phi(x), x >= kTailStart: from erfc, then (where erfc underflows) by
// Laplace's continued fraction R(x) = 1 / (x + 1 / (x + 2 / (x + 3 / (x + ...)))), whose 40
// levels are exact to rounding from 30 on.
double MillsRatio(double x) {
  if (x == kTruncInf) return 0.0;
  if (x < kDeepTail) return 0.5 * std::erfc(x * std::numbers::sqrt2 / 2.0) / StdNormalPdf(x);
  double t = x;
  for (int k = 40; k >= 1; --k) t = x + k / t;
  return 1.0 / t;
}

// Wide: Phi(b) - Phi(a) from the tail the interval lies in, via erfc, which keeps full relative
// precision in both tails; b - a > 1 keeps the difference from cancelling by more than a factor
// of ~3 there.
double WideMass(double a, double b) {
  const double r = std::numbers::sqrt2 / 2.0;  // 1 / sqrt(2)
  if (a >= 0.0) return 0.5 * (std::erfc(a * r) - std::erfc(b * r));
  if (b <= 0.0) return 0.5 * (std::erfc(-b * r) - std::erfc(-a * r));
  return 1.0 - 0.5 * std::erfc(-a * r) - 0.5 * std::erfc(b * r);
}

// Robert (1995), "Simulation of truncated normal variables", Stat. Comput. 5:121.
// One draw of N(0, 1) restricted to [a, b] (0 <= a < b, b may be +inf) by exponential rejection
// (Prop. 2.3): the proposal a + Exp(alpha) with the optimal rate alpha = (a + sqrt(a^2 + 4)) / 2,
// accepted with probability exp(-(z - alpha)^2 / 2); draws above b are rejected.
double SampleExponentialTail(double a, double b, double alpha, RandomStream& rng) {
  for (;;) {
    const double z = a - std::log1p(-rng.Uniform()) / alpha;  // Uniform() < 1: log1p finite
    const double u = rng.Uniform();
    if (z <= b && u < std::exp(-0.5 * (z - alpha) * (z - alpha))) return z;
  }
}

// Uniform rejection on [a, b] (Prop. 2.2): the envelope is phi at the point m of [a, b] nearest
// 0, so z is accepted with probability exp((m^2 - z^2) / 2).
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

}  // namespace

StandardTruncation TruncateStandardNormal(double a, double b) {
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
  t.mass = WideMass(a, b);
  const double pa = std::isfinite(a) ? StdNormalPdf(a) : 0.0;
  const double pb = std::isfinite(b) ? StdNormalPdf(b) : 0.0;
  const double apa = std::isfinite(a) ? a * pa : 0.0;
  const double bpb = std::isfinite(b) ? b * pb : 0.0;
  const double lambda = (pa - pb) / t.mass;
  t.mean = lambda;
  t.variance = std::max(1.0 + (apa - bpb) / t.mass - lambda * lambda, 0.0);
  return t;
}

double LogStandardNormalMass(double a, double b) {
  if (!(a < b)) return -kTruncInf;
  if (b <= 0.0) {  // a left tail is the mirror image of a right one
    const double lo = -b;
    b = -a;
    a = lo;
  }
  if (a < kTailStart) {
    return std::log(b - a <= kNarrowWidth ? TruncateStandardNormal(a, b).mass : WideMass(a, b));
  }
  // Z = phi(a) R(a) - phi(b) R(b) = phi(a) R(a) (1 - exp(-(b - a)(b + a) / 2) R(b) / R(a)): the
  // bracket by expm1 of its log, which keeps it accurate down to intervals far narrower than a
  // kernel's.
  const double ra = MillsRatio(a);
  const double log_ratio =
      b == kTruncInf ? -kTruncInf : -0.5 * (b - a) * (b + a) + std::log(MillsRatio(b) / ra);
  return -0.5 * a * a - kTruncLogSqrt2Pi + std::log(ra) + std::log(-std::expm1(log_ratio));
}

// Of the three exact rejection samplers above, uses the one with the highest acceptance rate for
// this interval (each has a closed form, so the choice is deterministic and the expected number of
// tries is at most about 2 for any interval; Robert 1995, Sec. 2):
//   normal rejection:       Z
//   uniform rejection:      Z / ((b - a) phi(m))
//   exponential (one tail): Z alpha sqrt(2 pi) exp(alpha a - alpha^2 / 2)   (a >= 0)
// A left tail (b <= 0) is the mirror image of a right one.
double SampleStandardTruncated(double a, double b, double log_mass, RandomStream& rng) {
  const bool mirror = b <= 0.0;  // sample -z on [-b, -a]
  const double lo = mirror ? -b : a, hi = mirror ? -a : b;
  const double log_normal_rate = log_mass;
  const double m = std::clamp(0.0, lo, hi);
  const double log_uniform_rate = log_mass - std::log(hi - lo) + 0.5 * m * m + kTruncLogSqrt2Pi;
  double log_exponential_rate = -kTruncInf, alpha = 0.0;
  if (lo >= 0.0) {
    alpha = 0.5 * (lo + std::sqrt(lo * lo + 4.0));
    log_exponential_rate =
        log_mass + std::log(alpha) + kTruncLogSqrt2Pi + alpha * lo - 0.5 * alpha * alpha;
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

}  // namespace combabc
