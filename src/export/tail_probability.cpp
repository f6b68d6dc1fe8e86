// Chi-square and F tail probabilities from the regularised incomplete gamma and beta functions
// (Numerical Recipes, 3rd ed., 6.2 and 6.4), for the fit checks.
#include "combabc/export/tail_probability.hpp"

#include <cmath>
#include <limits>

namespace combabc {
namespace {

constexpr double kNoProbability = std::numeric_limits<double>::quiet_NaN();
constexpr double kTiny = 1e-300;  // keeps the continued fractions' denominators off zero
constexpr double kEps = 1e-15;
constexpr int kMaxTerms = 10000;

// log Gamma(a) for a > 0 by Lanczos' series (g = 5, n = 6; Numerical Recipes 2nd ed. 6.1), to
// 2e-10 relative: ample for a verdict at a probability of 1e-3. Not std::lgamma, which may write
// the global signgam (POSIX): a data race wherever two threads check runs at once.
double LogGamma(double a) {
  static constexpr double kCoefficients[] = {76.18009172947146,
                                             -86.50532032941677,
                                             24.01409824083091,
                                             -1.231739572450155,
                                             0.1208650973866179e-2,
                                             -0.5395239384953e-5};
  double x = a;
  double y = a;
  const double t = x + 5.5 - (x + 0.5) * std::log(x + 5.5);
  double sum = 1.000000000190015;
  for (double c : kCoefficients) sum += c / ++y;
  return -t + std::log(2.5066282746310005 * sum / x);
}

// Q(a, x) = Gamma(a, x) / Gamma(a), the regularised upper incomplete gamma function.
double GammaQ(double a, double x) {
  if (x <= 0.0) return 1.0;
  const double log_prefix = -x + a * std::log(x) - LogGamma(a);
  if (x < a + 1.0) {
    // The series for P(a, x) converges fast here.
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < kMaxTerms; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * kEps) break;
    }
    return 1.0 - sum * std::exp(log_prefix);
  }
  // Lentz's continued fraction for Q(a, x).
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < kMaxTerms; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEps) break;
  }
  return std::exp(log_prefix) * h;
}

// The continued fraction of the incomplete beta function (Lentz), for x < (a + 1) / (a + b + 2).
double BetaFraction(double a, double b, double x) {
  const double qab = a + b;
  const double qap = a + 1.0;
  const double qam = a - 1.0;
  double c = 1.0;
  double d = 1.0 - qab * x / qap;
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m < kMaxTerms; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEps) break;
  }
  return h;
}

// I_x(a, b), the regularised incomplete beta function, 0 <= x <= 1.
double BetaI(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double log_front =
      LogGamma(a + b) - LogGamma(a) - LogGamma(b) + a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  // The fraction converges fast on one side of the mean; the symmetry I_x(a, b) = 1 - I_1-x(b, a)
  // serves the other.
  if (x < (a + 1.0) / (a + b + 2.0)) return front * BetaFraction(a, b, x) / a;
  return 1.0 - front * BetaFraction(b, a, 1.0 - x) / b;
}

}  // namespace

double ChiSquareUpperTail(double x, double dof) {
  if (std::isnan(x) || !(dof > 0.0)) return kNoProbability;
  if (std::isinf(x)) return x > 0.0 ? 0.0 : 1.0;
  return GammaQ(0.5 * dof, 0.5 * x);
}

double FUpperTail(double f, double d1, double d2) {
  if (std::isnan(f) || !(d1 > 0.0) || !(d2 > 0.0)) return kNoProbability;
  if (f <= 0.0) return 1.0;
  if (std::isinf(f)) return 0.0;
  // P(F >= f) = I_{d2 / (d2 + d1 f)}(d2 / 2, d1 / 2).
  return BetaI(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f));
}

}  // namespace combabc
