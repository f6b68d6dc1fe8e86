#include "proposals/gaussian_factor.hpp"

#include <Eigen/Cholesky>
#include <cmath>

#include "combabc/core/check.hpp"

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

}  // namespace combabc
