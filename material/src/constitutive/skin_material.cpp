#include <sflsh/core/error.hpp>
#include <sflsh/material/skin_material.hpp>

#include <cmath>
#include <limits>

namespace sflsh::material {

void validate(const SkinMaterial& material, const SkinMaterialNames& names) {
  // NaN fails every comparison, so each condition below also rejects NaN.
  require(std::isfinite(material.young_tangent) && material.young_tangent > 0.0,
          "{} must be a positive Young modulus in Pa, got {}", names.young_tangent, material.young_tangent);
  require(std::isfinite(material.young_normal) && material.young_normal > 0.0,
          "{} must be a positive Young modulus in Pa, got {}", names.young_normal, material.young_normal);
  require(material.poisson > -1.0 && material.poisson < 0.5,
          "{} must lie in (-1, 0.5) for a positive-definite stiffness, got {}", names.poisson, material.poisson);
  require(std::isfinite(material.saturation) && material.saturation > 0.0, "{} must be positive, got {}",
          names.saturation, material.saturation);
}

double unit_lame_mu(double poisson) { return 1.0 / (2.0 * (1.0 + poisson)); }  // docs/physics.md §1.2

double unit_lame_lambda(double poisson) {  // docs/physics.md §1.2
  return poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
}

double fung_scale_c(const SkinMaterial& material) {
  switch (material.fung_scale) {
    case FungScale::kTangentOverSaturation:
      return material.young_tangent / material.saturation;  // docs/physics.md §1.2
    case FungScale::kTangentTimesSaturation:
      return material.young_tangent * material.saturation;
    case FungScale::kNone:
      return std::numeric_limits<double>::infinity();
  }
  throw_error("unknown FungScale value {}", static_cast<int>(material.fung_scale));
}

OrthotropicConstants small_strain_constants(const SkinMaterial& material) {
  validate(material);
  // ℂ_ijkl = ℂ⁰_ijkl (E_i E_j E_k E_l)^{1/4} (Li & Barbič 2014; docs/physics.md §1.2). Its compliance is
  // D⁻¹ S⁰ D⁻¹ with D = diag(√E_i) and S⁰ the unit-Young isotropic compliance, so S_ij = −ν/√(E_i E_j) for
  // i ≠ j; with FEBio's S_ij = −ν_ij/E_i that is ν_ij = ν √(E_i/E_j). Shear: ℂ_ijij = μ₀ √(E_i E_j).
  const double nu = material.poisson;
  OrthotropicConstants k;
  k.E1 = material.young_tangent;
  k.E2 = material.young_tangent;
  k.E3 = material.young_normal;
  k.nu12 = nu * std::sqrt(k.E1 / k.E2);
  k.nu23 = nu * std::sqrt(k.E2 / k.E3);
  k.nu31 = nu * std::sqrt(k.E3 / k.E1);
  k.G12 = std::sqrt(k.E1 * k.E2) / (2.0 * (1.0 + nu));
  k.G23 = std::sqrt(k.E2 * k.E3) / (2.0 * (1.0 + nu));
  k.G31 = std::sqrt(k.E3 * k.E1) / (2.0 * (1.0 + nu));
  k.c = fung_scale_c(material);
  return k;
}

}  // namespace sflsh::material
