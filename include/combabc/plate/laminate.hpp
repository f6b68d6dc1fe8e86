#pragma once
// Equivalent single layer of a laminate of isotropic layers (classical laminated plate theory,
// Kirchhoff kinematics). The bending stiffness D is taken about the neutral plane of the
// laminate, so extension-bending coupling vanishes exactly when all layers share one Poisson ratio
// and is neglected otherwise (docs/model.md, "Laminate").
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace combabc::plate {

// One isotropic layer; SI units.
struct Layer {
  double thickness = 1.0e-3;      // m, in [1e-9, 1]
  double youngs_modulus = 1.0e7;  // Pa, in [1, 1e13]
  double poisson_ratio = 0.3;     // in (-1, 0.5)
  double density = 1000.0;        // kg/m^3, in [1e-3, 1e5]
  double loss_factor = 0.0;  // eta in [0, 10]: hysteretic damping, complex modulus E(1 + i eta)

  // Names the field and the violated constraint; `prefix` names the owner ("layers[1]").
  bool IsValid(std::string* why, const std::string& prefix = "Layer") const;
};

// Bending properties of the equivalent single layer: moment = -(D_real + i D_imag) curvature with
// curvature (w_xx, w_yy, 2 w_xy); and its transverse shear stiffness for first-order shear
// deformation theory: shear force = (S_real + i S_imag) shear strain, in both directions (the
// layers are isotropic, so A44 = A55 and A45 = 0).
struct PlateSection {
  Eigen::Matrix3d bending_real = Eigen::Matrix3d::Zero();  // N m
  Eigen::Matrix3d bending_imag = Eigen::Matrix3d::Zero();  // N m (loss part)
  double shear_real = 0.0;                                 // N/m
  double shear_imag = 0.0;                                 // N/m (loss part)
  double mass_per_area = 0.0;                              // kg/m^2 (rotary inertia neglected)
  double thickness = 0.0;                                  // m, total
  double neutral_plane = 0.0;                              // m above the bottom face
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
