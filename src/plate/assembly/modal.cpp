// Modal analysis: K phi = omega^2 M phi with the real (storage) stiffness, by shift-invert
// subspace iteration with Rayleigh-Ritz (Bathe's subspace iteration). The shifted matrix is real
// symmetric positive definite, so a sparse LDL^T is correct here (unlike the complex symmetric
// harmonic case).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/plate/assembly/plate.hpp"

namespace combabc::plate {
namespace {

// M = rho h M_1 + R: translational and rotary inertia, assembled apart so that the Kirchhoff
// mass (R = 0) stays bit-identical to rho h M_1.
Eigen::SparseMatrix<double> AssembleMass(const Plate& plate, const std::vector<int>& map, int n) {
  std::vector<Eigen::Triplet<double>> unit_triplets;
  std::vector<Eigen::Triplet<double>> rotary_triplets;
  for (int ex = 0; ex < plate.num_elements_x(); ++ex) {
    for (int ey = 0; ey < plate.num_elements_y(); ++ey) {
      const ElementMatrices& e = plate.Element(ex, ey);
      int global[kMaxElementDofs];
      for (int k = 0; k < plate.element_dofs(); ++k) global[k] = map[plate.ElementDof(ex, ey, k)];
      for (int c = 0; c < plate.element_dofs(); ++c) {
        if (global[c] < 0) continue;
        for (int r = 0; r < plate.element_dofs(); ++r) {
          if (global[r] < 0) continue;
          unit_triplets.emplace_back(global[r], global[c], e.mass_unit(r, c));
          if (e.rotary_inertia(r, c) != 0.0) {
            rotary_triplets.emplace_back(global[r], global[c], e.rotary_inertia(r, c));
          }
        }
      }
    }
  }
  Eigen::SparseMatrix<double> mass(n, n);
  mass.setFromTriplets(unit_triplets.begin(), unit_triplets.end());
  if (rotary_triplets.empty()) return mass * plate.section().mass_per_area;
  Eigen::SparseMatrix<double> rotary(n, n);
  rotary.setFromTriplets(rotary_triplets.begin(), rotary_triplets.end());
  return mass * plate.section().mass_per_area + rotary;
}

}  // namespace

Modes Plate::ComputeModes(const Constraints& constraints, int count) const {
  std::vector<int> free_dofs;
  Eigen::SparseMatrix<double> stiffness = DynamicStiffness(constraints, 0.0, &free_dofs).real();
  const int n = static_cast<int>(free_dofs.size());
  if (count < 1 || count > n) {
    throw Error(
        ErrorKind::kConfig, "mode count must be in [1, number of free dofs]", "", 0, "count");
  }
  std::vector<int> map(num_dofs(), -1);
  for (int k = 0; k < n; ++k) map[free_dofs[k]] = k;
  Eigen::SparseMatrix<double> mass = AssembleMass(*this, map, n);
  // Symmetric Jacobi scaling S K S y = lambda S M S y (x = S y): the BFS dofs carry different
  // units, and without it the definiteness test on the pivots is meaningless on graded meshes.
  const Eigen::VectorXd scale = stiffness.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  stiffness = scale.asDiagonal() * stiffness * scale.asDiagonal();
  mass = scale.asDiagonal() * mass * scale.asDiagonal();

  // Shift: none when K is positive definite; a small negative shift for a floating plate (rigid
  // body modes make K singular).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(stiffness);
  double shift = 0.0;
  const auto pivots_ok = [&]() {
    if (solver.info() != Eigen::Success) return false;
    const Eigen::VectorXd d = solver.vectorD();
    return d.minCoeff() > 1e-12 * d.cwiseAbs().maxCoeff();
  };
  if (!pivots_ok()) {
    shift = -1e-8 * stiffness.diagonal().sum() / mass.diagonal().sum();
    solver.compute(stiffness - shift * mass);
    if (!pivots_ok()) throw Error(ErrorKind::kSoftware, "shifted stiffness is not definite");
  }

  const int p = std::min(n, std::max(2 * count, count + 16));
  // Deterministic start (no RNG dependency): a fixed integer hash per entry.
  Eigen::MatrixXd x(n, p);
  for (int c = 0; c < p; ++c) {
    for (int r = 0; r < n; ++r) {
      std::uint32_t h =
          static_cast<std::uint32_t>(r) * 2654435761u ^ static_cast<std::uint32_t>(c + 1) * 40503u;
      h ^= h >> 13;
      h *= 0x5bd1e995u;
      h ^= h >> 15;
      x(r, c) = static_cast<double>(h) / 4294967296.0 - 0.5;
    }
  }
  Eigen::VectorXd previous = Eigen::VectorXd::Constant(count, -1.0);
  Eigen::VectorXd lambda;
  constexpr int kMaxIterations = 500;
  constexpr double kEigenvalueTol = 1e-10;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    const Eigen::MatrixXd y = solver.solve(mass * x);
    const Eigen::MatrixXd k_reduced = y.transpose() * (stiffness * y);
    const Eigen::MatrixXd m_reduced = y.transpose() * (mass * y);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ritz(
        0.5 * (k_reduced + k_reduced.transpose()), 0.5 * (m_reduced + m_reduced.transpose()));
    COMBABC_CHECK(ritz.info() == Eigen::Success);
    lambda = ritz.eigenvalues();
    x = y * ritz.eigenvectors();
    const Eigen::VectorXd head = lambda.head(count);
    const double change =
        ((head - previous).cwiseAbs().array() / head.cwiseAbs().array().max(1e-300)).maxCoeff();
    previous = head;
    if (change < kEigenvalueTol && iteration > 1) break;
  }
  Modes modes;
  modes.shapes = Eigen::MatrixXd::Zero(num_dofs(), count);
  for (int c = 0; c < count; ++c) {
    modes.frequencies_hz.push_back(std::sqrt(std::max(lambda(c), 0.0)) / (2.0 * M_PI));
    for (int k = 0; k < n; ++k) modes.shapes(free_dofs[k], c) = scale(k) * x(k, c);
  }
  return modes;
}

}  // namespace combabc::plate
