#include "proposals/weighted_logistic_regression.hpp"

#include <algorithm>
#include <cmath>

namespace combabc {
namespace {

// log(1 + e^z) without overflow for large |z|.
double Softplus(double z) { return std::max(z, 0.0) + std::log1p(std::exp(-std::abs(z))); }

double PenalisedLogLikelihood(const Eigen::MatrixXd& design,
                              const Eigen::VectorXd& y,
                              const Eigen::VectorXd& weights,
                              const Eigen::VectorXd& beta,
                              double ridge) {
  const Eigen::VectorXd eta = design * beta;
  double sum = 0.0;
  for (Eigen::Index u = 0; u < eta.size(); ++u) {
    sum += weights[u] * (y[u] * eta[u] - Softplus(eta[u]));
  }
  return sum - 0.5 * ridge * beta.tail(beta.size() - 1).squaredNorm();
}

}  // namespace

std::optional<Eigen::VectorXd> FitWeightedLogistic(const Eigen::MatrixXd& design,
                                                   const Eigen::VectorXd& y,
                                                   const Eigen::VectorXd& weights,
                                                   const Eigen::VectorXd& start,
                                                   const WeightedLogisticOptions& options) {
  const Eigen::Index num_coefficients = design.cols();
  Eigen::VectorXd beta = start;
  double objective = PenalisedLogLikelihood(design, y, weights, beta, options.ridge);
  if (!std::isfinite(objective)) return std::nullopt;

  // The ridge on the slopes only: the intercept carries the marginal and must stay free.
  Eigen::VectorXd penalty = Eigen::VectorXd::Constant(num_coefficients, options.ridge);
  penalty[0] = 0.0;

  Eigen::LDLT<Eigen::MatrixXd> solver(num_coefficients);
  Eigen::MatrixXd scaled(design.rows(), num_coefficients);
  Eigen::MatrixXd information(num_coefficients, num_coefficients);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const Eigen::ArrayXd eta = (design * beta).array();
    const Eigen::ArrayXd p = 1.0 / (1.0 + (-eta).exp());
    const Eigen::VectorXd residual = (weights.array() * (y.array() - p)).matrix();
    // Square roots of the IRLS weights w p (1 - p), so that the Hessian is a Gram matrix.
    const Eigen::VectorXd root = (weights.array() * p * (1.0 - p)).sqrt().matrix();

    const Eigen::VectorXd gradient = design.transpose() * residual - penalty.cwiseProduct(beta);
    scaled.noalias() = root.asDiagonal() * design;
    // The designs are narrow (at most max_predecessors + 1 columns, usually a few hundred rows or
    // fewer): a coefficient-wise product beats a blocked one, which spends its time packing.
    information.noalias() = scaled.transpose().lazyProduct(scaled);
    information.diagonal() += penalty;
    solver.compute(information);
    if (solver.info() != Eigen::Success) return std::nullopt;
    const Eigen::VectorXd step = solver.solve(gradient);
    if (!step.allFinite()) return std::nullopt;

    // Converged when the Newton decrement g' H^-1 g (twice the gain the step promises) is below
    // the log-likelihood's rounding: the step is then taken as it is, since the ascent test below
    // cannot tell it from noise (Boyd & Vandenberghe 2004, Convex Optimization, Sec. 9.5.1).
    if (gradient.dot(step) < options.tolerance) {
      beta += step;
      return beta.allFinite() ? std::optional<Eigen::VectorXd>(beta) : std::nullopt;
    }
    // Close to the optimum (decrement below 1e-3 per unit of total weight) the full Newton step is
    // taken without evaluating the objective: that evaluation, one log and one exp per row, was
    // most of the fit's cost. Any coefficients give an exact proposal density, so this trades
    // nothing in correctness.
    if (gradient.dot(step) < 1e-3) {
      beta += step;
      if (!beta.allFinite()) return std::nullopt;
      continue;
    }
    // Step halving: the penalised log-likelihood is strictly concave, but a full Newton step from
    // far away (nearly separable data) can overshoot it.
    double length = 1.0;
    bool ascended = false;
    for (int halving = 0; halving < 40 && !ascended; ++halving, length *= 0.5) {
      const Eigen::VectorXd trial = beta + length * step;
      const double trial_objective =
          PenalisedLogLikelihood(design, y, weights, trial, options.ridge);
      if (std::isfinite(trial_objective) && trial_objective >= objective) {
        beta = trial;
        objective = trial_objective;
        ascended = true;
      }
    }
    if (!ascended) return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace combabc
