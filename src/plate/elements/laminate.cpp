#include "combabc/plate/elements/laminate.hpp"

#include <array>
#include <cmath>
#include <sstream>

#include "combabc/core/check.hpp"

namespace combabc::plate {
namespace {

bool FailLayer(ValidationError* error, const char* field, double value, const char* constraint) {
  if (error != nullptr) {
    std::ostringstream os;
    os << value;
    *error = {"Layer", field, os.str(), constraint};
  }
  return false;
}

// Plane-stress reduced stiffness of an isotropic layer per unit modulus.
Eigen::Matrix3d ReducedStiffnessShape(double nu) {
  Eigen::Matrix3d q;
  q << 1.0, nu, 0.0, nu, 1.0, 0.0, 0.0, 0.0, 0.5 * (1.0 - nu);
  return q / (1.0 - nu * nu);
}

// Transverse shear stiffness S of the laminate (N/m), energy-consistent: the shear stress across
// the thickness is taken from equilibrium with the bending stresses of classical lamination
// theory in cylindrical bending, tau(z) = Q g(z) with g(z) = -(1 / D11) integral from the bottom
// to z of Q11(zeta) (zeta - z_n) dzeta, and S is chosen so that the first-order theory stores the
// same shear energy for the same shear force Q: 1 / S = integral of g(z)^2 / G(z) dz (Whitney,
// J. Appl. Mech. 40 (1973) 302-304; Vlachoutsis, Int. J. Numer. Meth. Eng. 33 (1992) 1537-1552).
// One layer gives S = 5/6 G h; a sandwich with a soft core gives about G_core d^2 / c, the
// sandwich-beam value (Allen 1969). Elastic moduli, so S_real does not depend on the loss factors
// (as D_real does not: the continuous-unknowns path relies on it). The loss part weights each
// layer's loss factor by its share of the shear energy (Ungar & Kerwin, J. Acoust. Soc. Am. 34
// (1962) 954-957), as D_imag = sum eta_k D_k does for bending; one loss factor eta for every layer
// gives S_imag = eta S_real exactly.
void ShearStiffness(const std::vector<Layer>& layers, PlateSection* section) {
  // 3-point Gauss-Legendre on [0, 1]: exact for g^2, a polynomial of degree 4 in each layer.
  constexpr std::array<double, 3> kPoint = {0.1127016653792583, 0.5, 0.8872983346207417};
  constexpr std::array<double, 3> kWeight = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
  const double d11 = section->bending_real(0, 0);
  double compliance = 0.0;
  double loss_compliance = 0.0;
  double g_bottom = 0.0;
  double z = 0.0;
  for (const Layer& layer : layers) {
    const double q11 = layer.youngs_modulus / (1.0 - layer.poisson_ratio * layer.poisson_ratio);
    const double shear_modulus = layer.youngs_modulus / (2.0 * (1.0 + layer.poisson_ratio));
    const double zb = z - section->neutral_plane;
    auto g = [&](double t) {  // t in [0, thickness] from the layer's bottom
      const double zz = zb + t;
      return g_bottom - q11 / d11 * (0.5 * (zz * zz - zb * zb));
    };
    double layer_compliance = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double gk = g(kPoint[k] * layer.thickness);
      layer_compliance += kWeight[k] * layer.thickness * gk * gk / shear_modulus;
    }
    compliance += layer_compliance;
    loss_compliance += layer.loss_factor * layer_compliance;
    g_bottom = g(layer.thickness);
    z += layer.thickness;
  }
  section->shear_real = 1.0 / compliance;
  section->shear_imag = section->shear_real * (loss_compliance / compliance);
}

// The refined zigzag theory's stiffnesses (laminate.hpp, PlateSection::zigzag_*). The integrands
// are at most quadratic in z within a layer (z and phi are linear there), so 2-point Gauss is
// exact.
void ZigzagStiffness(const std::vector<Layer>& layers, PlateSection* section) {
  constexpr std::array<double, 2> kPoint = {0.2113248654051871, 0.7886751345948129};
  double compliance = 0.0;  // sum h_k / G_k
  for (const Layer& layer : layers) {
    compliance += layer.thickness * 2.0 * (1.0 + layer.poisson_ratio) / layer.youngs_modulus;
  }
  const double mean_shear = section->thickness / compliance;
  std::vector<double> slope;
  bool zigzag = false;
  for (const Layer& layer : layers) {
    const double shear_modulus = layer.youngs_modulus / (2.0 * (1.0 + layer.poisson_ratio));
    slope.push_back(mean_shear / shear_modulus - 1.0);
    zigzag = zigzag || std::abs(slope.back()) > 1e-6;
  }
  if (!zigzag) slope.assign(layers.size(), 0.0);
  double phi_bottom = 0.0;
  double z = 0.0;
  for (std::size_t k = 0; k < layers.size(); ++k) {
    const Layer& layer = layers[k];
    const Eigen::Matrix3d q = layer.youngs_modulus * ReducedStiffnessShape(layer.poisson_ratio);
    const double shear_modulus = layer.youngs_modulus / (2.0 * (1.0 + layer.poisson_ratio));
    double z_phi = 0.0;
    double phi_phi = 0.0;
    double z_z = 0.0;
    // Integrals of the zigzag inertia (PlateSection::zigzag_inertia): the same ones, by density.
    for (double point : kPoint) {
      const double t = point * layer.thickness;
      const double zz = z + t - section->neutral_plane;
      const double phi = phi_bottom + slope[k] * t;
      z_phi += 0.5 * layer.thickness * zz * phi;
      phi_phi += 0.5 * layer.thickness * phi * phi;
      z_z += 0.5 * layer.thickness * zz * zz;
    }
    PlateSection::Matrix6d bending = PlateSection::Matrix6d::Zero();
    bending.topLeftCorner<3, 3>() = z_z * q;
    bending.topRightCorner<3, 3>() = -z_phi * q;
    bending.bottomLeftCorner<3, 3>() = -z_phi * q;
    bending.bottomRightCorner<3, 3>() = phi_phi * q;
    Eigen::Matrix2d shear;
    shear << 1.0, slope[k], slope[k], slope[k] * slope[k];
    shear *= shear_modulus * layer.thickness;
    section->zigzag_bending_real += bending;
    section->zigzag_bending_imag += layer.loss_factor * bending;
    section->zigzag_shear_real += shear;
    section->zigzag_shear_imag += layer.loss_factor * shear;
    Eigen::Matrix2d inertia;
    inertia << z_z, -z_phi, -z_phi, phi_phi;
    section->zigzag_inertia += layer.density * inertia;
    phi_bottom += slope[k] * layer.thickness;
    z += layer.thickness;
  }
  // The theta block is the classical D (same integral; taken from there so both are one number).
  section->zigzag_bending_real.topLeftCorner<3, 3>() = section->bending_real;
  section->zigzag_bending_imag.topLeftCorner<3, 3>() = section->bending_imag;
  section->zigzag_inertia(0, 0) = section->rotary_inertia;
  if (!zigzag) {
    // psi moves nothing: uncoupled stiffnesses of its own (the theta ones), so that it stays
    // zero. The bending part is needed too: the tied shear strains see only edge midpoint values.
    section->zigzag_shear_real(1, 1) = section->zigzag_shear_real(0, 0);
    section->zigzag_shear_imag(1, 1) = section->zigzag_shear_imag(0, 0);
    section->zigzag_bending_real.bottomRightCorner<3, 3>() = section->bending_real;
    section->zigzag_bending_imag.bottomRightCorner<3, 3>() = section->bending_imag;
  }
}

}  // namespace

bool Layer::IsValid(std::string* why, const std::string& prefix) const {
  ValidationError error;
  const bool valid = IsValid(&error);
  error.owner = prefix;
  return ExplainValidation(valid, error, why);
}

bool Layer::IsValid(ValidationError* error) const {
  // Physical ranges, generous enough for any laminate (from foams to steel, nanometre films to
  // metre-thick slabs) and tight enough that the stiffness and mass stay finite doubles.
  if (!(thickness >= 1e-9 && thickness <= 1.0)) {
    return FailLayer(error, "thickness", thickness, "must be in [1e-9, 1] m");
  }
  if (!(youngs_modulus >= 1.0 && youngs_modulus <= 1e13)) {
    return FailLayer(error, "youngs_modulus", youngs_modulus, "must be in [1, 1e13] Pa");
  }
  if (!(poisson_ratio > -1.0 && poisson_ratio < 0.5)) {
    return FailLayer(error, "poisson_ratio", poisson_ratio, "must be in (-1, 0.5)");
  }
  if (!(density >= 1e-3 && density <= 1e5)) {
    return FailLayer(error, "density", density, "must be in [1e-3, 1e5] kg/m^3");
  }
  if (!(loss_factor >= 0.0 && loss_factor <= 10.0)) {
    return FailLayer(error, "loss_factor", loss_factor, "must be in [0, 10]");
  }
  return true;
}

PlateSection EquivalentSingleLayer(const std::vector<Layer>& layers) {
  COMBABC_CHECK(!layers.empty());
  // Neutral plane: the height where the E/(1-nu^2)-weighted first moment vanishes.
  double weight = 0.0;
  double first_moment = 0.0;
  double z = 0.0;
  PlateSection section;
  for (const Layer& layer : layers) {
    const double q11 = layer.youngs_modulus / (1.0 - layer.poisson_ratio * layer.poisson_ratio);
    weight += q11 * layer.thickness;
    first_moment += q11 * layer.thickness * (z + 0.5 * layer.thickness);
    section.mass_per_area += layer.density * layer.thickness;
    z += layer.thickness;
  }
  section.thickness = z;
  section.neutral_plane = first_moment / weight;
  z = 0.0;
  for (const Layer& layer : layers) {
    const double bottom = z - section.neutral_plane;
    const double top = bottom + layer.thickness;
    const double second_moment = (top * top * top - bottom * bottom * bottom) / 3.0;
    const Eigen::Matrix3d d =
        layer.youngs_modulus * second_moment * ReducedStiffnessShape(layer.poisson_ratio);
    section.bending_real += d;
    section.bending_imag += layer.loss_factor * d;
    section.rotary_inertia += layer.density * second_moment;
    z += layer.thickness;
  }
  ShearStiffness(layers, &section);
  ZigzagStiffness(layers, &section);
  return section;
}

PlateSection IsotropicSection(double thickness,
                              double youngs_modulus,
                              double poisson_ratio,
                              double density,
                              double loss_factor) {
  Layer layer;
  layer.thickness = thickness;
  layer.youngs_modulus = youngs_modulus;
  layer.poisson_ratio = poisson_ratio;
  layer.density = density;
  layer.loss_factor = loss_factor;
  return EquivalentSingleLayer({layer});
}

}  // namespace combabc::plate
