#pragma once
// Equivalent single layer of a laminate of isotropic layers (classical laminated plate theory,
// Kirchhoff kinematics). The bending stiffness D is taken about the neutral plane of the
// laminate, so extension-bending coupling vanishes exactly when all layers share one Poisson ratio
// and is neglected otherwise (docs/model.md, "Laminate").
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "combabc/core/validation_error.hpp"

namespace combabc::plate {

// One isotropic layer; SI units.
struct Layer {
  double thickness = 1.0e-3;      // m, in [1e-9, 1]
  double youngs_modulus = 1.0e7;  // Pa, in [1, 1e13]
  double poisson_ratio = 0.3;     // in (-1, 0.5)
  double density = 1000.0;        // kg/m^3, in [1e-3, 1e5]
  double loss_factor = 0.0;  // eta in [0, 10]: hysteretic damping, complex modulus E(1 + i eta)

  // Names the field and the violated constraint (owner "Layer").
  bool IsValid(ValidationError* error) const;
  // The same as one sentence, `prefix` naming the owner: "Layer::thickness = 2; must be ...".
  bool IsValid(std::string* why, const std::string& prefix = "Layer") const;
};

// Bending properties of the equivalent single layer: moment = -(D_real + i D_imag) curvature with
// curvature (w_xx, w_yy, 2 w_xy); and its transverse shear stiffness for first-order shear
// deformation theory: shear force = (S_real + i S_imag) shear strain, in both directions (the
// layers are isotropic, so A44 = A55 and A45 = 0).
struct PlateSection {
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  Eigen::Matrix3d bending_real = Eigen::Matrix3d::Zero();  // N m
  Eigen::Matrix3d bending_imag = Eigen::Matrix3d::Zero();  // N m (loss part)
  double shear_real = 0.0;                                 // N/m
  double shear_imag = 0.0;                                 // N/m (loss part)
  double mass_per_area = 0.0;                              // kg/m^2, sum rho_k h_k
  // Rotary inertia of the normal, sum rho_k int (z - z_n)^2 dz (kg, i.e. kg m^2 per m^2): the
  // kinetic energy of the in-plane motion -z phi of the first-order theory (z about the neutral
  // plane, as D; the first mass moment of an unsymmetric laminate, which couples to the membrane
  // motion, is neglected with the membrane stiffness).
  double rotary_inertia = 0.0;
  double thickness = 0.0;      // m, total
  double neutral_plane = 0.0;  // m above the bottom face

  // Refined zigzag theory (Tessler, Di Sciuva & Gherlone, J. Compos. Mater. 44 (2010) 1303;
  // docs/model.md, "Plate theories"): in-plane displacements -z theta + phi(z) psi, phi the
  // piecewise-linear zigzag function, zero on both faces, of slope beta_k = G / G_k - 1 in layer
  // k (G the thickness-harmonic mean of the layers' shear moduli; z from the neutral plane).
  // zigzag_bending acts on (theta_x,x, theta_y,y, theta_x,y + theta_y,x, the same of psi):
  // [[D, -sum Q_k int z phi], [-sum Q_k int z phi, sum Q_k int phi^2]] (N m; its top left block
  // is bending_real); zigzag_shear on (w_,a - theta_a, psi_a) in each direction a:
  // [[sum G_k h_k, sum G_k beta_k h_k], [., sum G_k beta_k^2 h_k]] (N/m). The zigzag function
  // comes from the elastic moduli; the loss parts weight each layer's loss factor by its share
  // (complex moduli E_k (1 + i eta_k) with phi fixed). Without a zigzag (every |beta_k| below
  // 1e-6: equal shear moduli) psi moves nothing; it is then given the shear stiffness sum G_k h_k
  // and the bending stiffness D of its own, uncoupled, so that it stays zero instead of making
  // the stiffness singular (RZT is then FSDT without a shear correction factor).
  Matrix6d zigzag_bending_real = Matrix6d::Zero();
  Matrix6d zigzag_bending_imag = Matrix6d::Zero();
  Eigen::Matrix2d zigzag_shear_real = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d zigzag_shear_imag = Eigen::Matrix2d::Zero();
  // Inertia of the zigzag kinematics on (theta_a, psi_a) in each direction a, from the kinetic
  // energy of u_a = -z theta_a + phi psi_a: [[sum rho_k int z^2, -sum rho_k int z phi],
  // [., sum rho_k int phi^2]] (kg; top left = rotary_inertia).
  Eigen::Matrix2d zigzag_inertia = Eigen::Matrix2d::Zero();
};

// Layers are listed from the bottom face up. The shear stiffness is energy-consistent (see
// laminate.cpp): 5/6 G h for a single layer; for a sandwich it follows the soft core.
PlateSection EquivalentSingleLayer(const std::vector<Layer>& layers);

// Homogeneous isotropic plate, D = E h^3 / (12 (1 - nu^2)).
PlateSection IsotropicSection(double thickness,
                              double youngs_modulus,
                              double poisson_ratio,
                              double density,
                              double loss_factor = 0.0);

}  // namespace combabc::plate
