#pragma once
// Exact 3D elasticity solution of a simply supported rectangular laminate of isotropic layers
// under the sinusoidal load q0 sin(pi x / a) sin(pi y / b) on its top face (Pagano, J. Compos.
// Mater. 4 (1970) 20-34, there for orthotropic layers; here for isotropic ones). The reference for
// the plate theories' model error in tests/plate/fsdt_validation_test.cpp and docs/model.md.
//
// Method (the transfer-matrix form of Pagano's solution): with u = U(z) cos px sin qy,
// v = V(z) sin px cos qy, w = W(z) sin px sin qy and the stresses tau_xz = X cos sin,
// tau_yz = Y sin cos, sigma_z = S sin sin (p = pi / a, q = pi / b), 3D elasticity and
// equilibrium reduce in each layer to s' = A s for s = (U, V, W, X, Y, S), a constant 6 x 6 A.
// The state is continuous across interfaces, so s(top) = T s(bottom) with T the product of the
// layers' exp(A h_k). The faces are free of shear, the bottom of normal stress and the top
// carries S = q0: three equations for U, V, W at the bottom. These edge conditions (w = sigma_n =
// tangential displacement = 0) are the 3D simply supported ones that every term satisfies.
#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "combabc/plate/elements/laminate.hpp"

namespace combabc::plate::testing {

// w at height z (m above the bottom face) at the plate's centre, for load amplitude q0 (Pa) in
// the +w direction. Internally scaled (lengths by the total thickness, stresses by the first
// layer's modulus) so the 6 x 6 algebra stays well conditioned.
//
// normal_stiffening F > 1 makes every layer stiffer through the thickness only: C33 = F c and
// C13 = sqrt(F) lambda (c = lambda + 2 mu), so the plane-stress in-plane stiffness
// C_ab - C_a3 C_b3 / C33 and the shear moduli stay the layer's own while the transverse normal
// strain goes to zero as F grows: the 3D answer of a laminate without thickness stretch, which
// isolates what the plate theories neglect by assuming w constant through the thickness.
inline double ExactCentreDeflection(const std::vector<Layer>& layers,
                                    double a,
                                    double b,
                                    double q0,
                                    double z,
                                    double normal_stiffening = 1.0) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  double h = 0.0;
  for (const Layer& layer : layers) h += layer.thickness;
  const double e_ref = layers.front().youngs_modulus;
  const double p = M_PI / a * h;
  const double q = M_PI / b * h;
  auto layer_matrix = [&](const Layer& layer) {
    const double e = layer.youngs_modulus / e_ref;
    const double nu = layer.poisson_ratio;
    const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    const double mu = e / (2.0 * (1.0 + nu));
    const double c = lambda + 2.0 * mu;
    const double c33 = normal_stiffening * c;
    const double c13 = std::sqrt(normal_stiffening) * lambda;
    // Row of W' in terms of s, then the rows that use it.
    Eigen::Matrix<double, 1, 6> w_prime;
    w_prime << c13 * p / c33, c13 * q / c33, 0.0, 0.0, 0.0, 1.0 / c33;
    Matrix6 m = Matrix6::Zero();
    m(0, 2) = -p;
    m(0, 3) = 1.0 / mu;
    m(1, 2) = -q;
    m(1, 4) = 1.0 / mu;
    m.row(2) = w_prime;
    m(3, 0) = c * p * p + mu * q * q;
    m(3, 1) = lambda * p * q + mu * p * q;
    m.row(3) -= c13 * p * w_prime;
    m(4, 0) = lambda * p * q + mu * p * q;
    m(4, 1) = c * q * q + mu * p * p;
    m.row(4) -= c13 * q * w_prime;
    m(5, 3) = p;
    m(5, 4) = q;
    return m;
  };
  // Transfer matrices to the top and to height z.
  Matrix6 to_top = Matrix6::Identity();
  Matrix6 to_z = Matrix6::Identity();
  double bottom = 0.0;
  for (const Layer& layer : layers) {
    const Matrix6 a_k = layer_matrix(layer);
    const double t = layer.thickness / h;
    to_top = (a_k * t).exp() * to_top;
    const double top = bottom + layer.thickness;
    if (z >= top) {
      to_z = (a_k * t).exp() * to_z;
    } else if (z > bottom) {
      to_z = (a_k * ((z - bottom) / h)).exp() * to_z;
    }
    bottom = top;
  }
  // Bottom state (U, V, W, 0, 0, 0); top rows X, Y, S = (0, 0, q0 / e_ref).
  const Eigen::Matrix3d system = to_top.block<3, 3>(3, 0);
  const Eigen::Vector3d bottom_state =
      system.fullPivLu().solve(Eigen::Vector3d(0.0, 0.0, q0 / e_ref));
  const Eigen::Matrix<double, 6, 1> s = to_z.leftCols<3>() * bottom_state;
  return s(2) * h;  // W was in units of h
}

}  // namespace combabc::plate::testing
