#include "proposals/gaussian_factor.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "params/truncated_normal.hpp"

namespace combabc {
namespace {

// Regularisation of a kernel covariance Sigma, in units of each real's prior standard deviation
// tau_k (finite for every valid prior). A population says nothing about the scale of a coordinate
// in which all its particles agree (one particle; all the weight on one particle; OLCM with a
// single particle within the next thresholds), and a population of N <= d particles spans at most
// N - 1 directions. So:
//  1. a coordinate whose variance is at most (kCollapsedSd tau_k)^2 is collapsed: its row and
//     column are replaced by the prior's scale, (kFallbackSd tau_k)^2 on the diagonal and no
//     correlation, so the next wave can move again (a tenth of the prior, to stay local);
//  2. (kCollapsedSd tau_k)^2 is then added to every diagonal entry, which makes a rank-deficient
//     covariance positive definite while changing any posterior-sized one negligibly (a posterior
//     1e-6 as wide as its prior is far beyond what ABC reaches).
// Should rounding still defeat the Cholesky factorisation, the added multiple grows by 100 until
// it succeeds.
constexpr double kCollapsedSd = 1e-6;
constexpr double kFallbackSd = 0.1;

// LogBoxMass skips a coordinate whose interval reaches beyond this many (conditional) sd on both
// sides: its mass is 1 - 2 Q(8.5) > 1 - 2e-17, and log of it is lost in rounding anyway.
constexpr double kFarSd = 8.5;
constexpr double kBoxInf = std::numeric_limits<double>::infinity();
// TruncateEachCoordinate: the probe's draws and stream, and the inside fraction below which a
// kernel truncates. At 2% a whole redraw needs 50 tries on average and never reaches
// kMaxSupportTries (0.98^10000 ~ 1e-88); 2000 draws put ~40 inside at the threshold.
constexpr int kProbeDraws = 2000;
constexpr std::uint64_t kProbeSeed = 0xB0C5ULL;
constexpr double kMinInsideFraction = 0.02;

}  // namespace

Factor Factorise(Eigen::MatrixXd sigma, const std::vector<double>& prior_sd) {
  const Eigen::Index d = sigma.rows();
  for (Eigen::Index k = 0; k < d; ++k) {
    const double tau = prior_sd[static_cast<std::size_t>(k)];
    if (!(sigma(k, k) > kCollapsedSd * kCollapsedSd * tau * tau)) {  // also catches NaN
      sigma.row(k).setZero();
      sigma.col(k).setZero();
      sigma(k, k) = kFallbackSd * kFallbackSd * tau * tau;
    }
  }
  for (double ridge = kCollapsedSd * kCollapsedSd;; ridge *= 100.0) {
    Eigen::MatrixXd regularised = sigma;
    for (Eigen::Index k = 0; k < d; ++k) {
      const double tau = prior_sd[static_cast<std::size_t>(k)];
      regularised(k, k) += ridge * tau * tau;
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(regularised);
    const Eigen::MatrixXd l = llt.matrixL();
    if (llt.info() == Eigen::Success && (l.diagonal().array() > 0.0).all() && l.allFinite()) {
      const Eigen::MatrixXd l_inv =
          l.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(d, d));
      Factor f;
      for (Eigen::Index i = 0; i < d; ++i) {
        for (Eigen::Index k = 0; k <= i; ++k) {
          f.l.push_back(l(i, k));
          f.l_inv.push_back(l_inv(i, k));
        }
        f.log_det += std::log(l(i, i));
      }
      return f;
    }
    COMBABC_CHECK(ridge < 1e6);  // with ridge ~ tau^2 a covariance of particles is always PD
  }
}

std::vector<double> PriorSd(const ParameterSpace& space) {
  std::vector<double> sd;
  for (const ContinuousParameter& p : space.reals()) sd.push_back(p.prior.StandardDeviation());
  return sd;
}

Box SupportBox(const RealsPrior& prior) {
  Box box;
  for (std::size_t k = 0; k < prior.dimension(); ++k) {
    const ContinuousPrior& p = prior.marginal(k);
    double low = -kBoxInf, high = kBoxInf;
    switch (p.kind) {
      case PriorKind::kUniform:
      case PriorKind::kTruncatedNormal:
      case PriorKind::kJoint:
        low = p.low;
        high = p.high;
        break;
      case PriorKind::kLogNormal:
        low = 0.0;  // open: SampleInBox redraws an exact 0
        break;
      case PriorKind::kNormal:
        break;
    }
    box.low.push_back(low);
    box.high.push_back(high);
    box.bounded.push_back(std::isfinite(low) || std::isfinite(high) ? 1 : 0);
    box.marginal.push_back(p);
  }
  return box;
}

void SampleGaussian(const Factor& f, const double* c, RandomStream& rng, std::span<double> r) {
  const std::size_t d = r.size();
  for (std::size_t i = 0; i < d; ++i) r[i] = rng.Normal();
  // r = c + L z in place: row i needs z_0..z_i only, so fill from the last row up.
  for (std::size_t i = d; i-- > 0;) {
    double x = c[i];
    for (std::size_t k = 0; k <= i; ++k) x += f.l[Tri(i, k)] * r[k];
    r[i] = x;
  }
}

bool TruncateEachCoordinate(const std::vector<double>& cumulative,
                            const std::vector<double>& centres,
                            const std::function<const Factor&(std::size_t)>& factor_of,
                            const Box& box) {
  const std::size_t d = box.low.size();
  if (d == 0 || cumulative.empty()) return false;
  bool bounded = false;
  for (const std::uint8_t b : box.bounded) bounded = bounded || b;
  if (!bounded) return false;
  RandomStream rng(kProbeSeed, 0, 0);
  std::vector<double> r(d);
  int inside = 0;
  for (int t = 0; t < kProbeDraws; ++t) {
    const double u = rng.Uniform() * cumulative.back();
    const std::size_t j = std::min<std::size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(),
        cumulative.size() - 1);
    SampleGaussian(factor_of(j), &centres[j * d], rng, r);
    bool in = true;
    for (std::size_t i = 0; i < d && in; ++i) in = box.marginal[i].InSupport(r[i]);
    inside += in ? 1 : 0;
  }
  return inside < kMinInsideFraction * kProbeDraws;
}

void SampleInBox(const Factor& f,
                 const double* c,
                 const Box& box,
                 RandomStream& rng,
                 std::span<double> r,
                 std::span<double> z) {
  const std::size_t d = r.size();
  for (std::size_t i = 0; i < d; ++i) {
    double m = c[i];  // r_i's mean given z_0..z_{i-1}
    for (std::size_t k = 0; k < i; ++k) m += f.l[Tri(i, k)] * z[k];
    const double l_ii = f.l[Tri(i, i)];
    if (!box.bounded[i]) {
      z[i] = rng.Normal();
      r[i] = m + l_ii * z[i];
      continue;
    }
    const double a = (box.low[i] - m) / l_ii, b = (box.high[i] - m) / l_ii;
    const double log_mass = LogStandardNormalMass(a, b);
    // z is inside [a, b], but m + l_ii z may round onto an open end or a hair outside a closed
    // one: such a draw (of probability ~1e-16) is drawn again, which changes the density by as
    // little.
    for (int attempt = 0;; ++attempt) {
      if (attempt == kMaxSupportTries || !(log_mass > -kBoxInf)) {
        throw Error(ErrorKind::kSoftware,
                    "Gaussian proposal: coordinate " + std::to_string(i) +
                        " has no room inside its bounds (kernel sd " + std::to_string(l_ii) + ")");
      }
      z[i] = SampleStandardTruncated(a, b, log_mass, rng);
      r[i] = m + l_ii * z[i];
      if (box.marginal[i].InSupport(r[i])) break;
    }
  }
}

double LogBoxMass(
    const Factor& f, const Box& box, std::span<const double> r, const double* y, const double* w) {
  double sum = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!box.bounded[i]) continue;
    const double z = w ? y[i] - w[i] : y[i];
    const double l_ii = f.l[Tri(i, i)];
    // r_i's conditional mean is r_i - l_ii z_i, so the interval is (bound - r_i) / l_ii + z_i.
    const double a = (box.low[i] - r[i]) / l_ii + z, b = (box.high[i] - r[i]) / l_ii + z;
    if (a <= -kFarSd && b >= kFarSd) continue;
    sum += LogStandardNormalMass(a, b);
  }
  return sum;
}

}  // namespace combabc
