#pragma once
// Weighted ridge logistic regression by Newton-Raphson, the fitting step of the logistic-
// conditionals kernel (Schäfer & Chopin 2013, "Sequential Monte Carlo on large binary sampling
// spaces", Statistics and Computing 23:163-184, who fit each conditional by Newton-Raphson on the
// weighted particles). Private to the proposals layer.
#include <Eigen/Dense>
#include <optional>

namespace combabc {

struct WeightedLogisticOptions {
  // Penalty (ridge / 2) |slopes|^2; the intercept (column 0) is not penalised.
  double ridge = 1e-3;
  int max_iterations = 50;
  // Converged once the Newton decrement g' H^-1 g (twice the gain the next step promises) is below
  // this. The weights sum to 1, so the log-likelihood is O(1); near the optimum the decrement falls
  // quadratically (~1e-6, ~1e-12, ~1e-24), so the test costs at most one extra iteration.
  double tolerance = 1e-10;
};

// Maximises the penalised weighted log-likelihood
//   L(beta) = sum_u w_u [y_u eta_u - log(1 + exp(eta_u))] - ridge / 2 sum_{k >= 1} beta_k^2,
//   eta = design * beta,
// where column 0 of `design` is the intercept (all ones), y_u is in [0, 1] (a fraction of ones
// where rows with equal design rows were merged, w_u then their summed weight) and w_u >= 0. Starts
// from `start`; each Newton step is halved until L does not decrease, so the iteration
// ascends monotonically. nullopt when it has not converged within max_iterations or produced a
// non-finite number: the caller then falls back to something simpler.
std::optional<Eigen::VectorXd> FitWeightedLogistic(const Eigen::MatrixXd& design,
                                                   const Eigen::VectorXd& y,
                                                   const Eigen::VectorXd& weights,
                                                   const Eigen::VectorXd& start,
                                                   const WeightedLogisticOptions& options);

}  // namespace combabc
