#pragma once
// The skin material of one point: SFLSH §3 ("orthotropic Saint Venant–Kirchhoff model with Fung-type
// saturation", after Romero et al. 2020) with tangential and normal Young moduli, Poisson's ratio 0.2
// and Fung saturation 4. The energy itself is in orthotropic_fung.hpp; this header holds the
// parameters, their validation, and the small-strain constants that map them onto other FEM codes.
//
// Units: Young moduli, shear moduli and c are in Pa (stress units); the energy density is in J/m³.
// The thickness fraction h of SFLSH's κ = (h, Y_t, Y_n) is geometry (it moves the inner surface,
// docs/physics.md §1.4), not part of the energy, so it is not a field here.
#include <string_view>

namespace sflsh::material {

/// How the Fung scale c (stress units) is derived from the parameters. docs/physics.md §1.2 proposes
/// c = Y_t / saturation; what SFLSH's "saturation = 4" multiplies is not published (docs/physics.md §6.1),
/// so the reading is a choice.
enum class FungScale {
  kTangentOverSaturation,  ///< c = Y_t / s (default, docs/physics.md §1.2): exponent ≈ s·ε² in tangential stretch
  kTangentTimesSaturation,  ///< c = s·Y_t: the alternative reading (saturation sets in ~s² times later)
  kNone,                    ///< c = ∞: Fung factor off, Ψ = Ψ₀ (plain orthotropic StVK)
};

/// What the evaluation does when the Fung exponent 2Ψ₀/c exceeds kFungExponentCap.
enum class ExponentOverflow {
  kThrow,             ///< throw sflsh::Error naming the exponent (default: such strains mean a broken state)
  kContinueLinearly,  ///< continue exp(x) by its tangent line beyond the cap: Ψ, P and dP/dF stay finite
                      ///< and mutually consistent (C¹ in x), and the energy keeps growing with strain
};

/// The cap on the Fung exponent x = 2Ψ₀/c. exp(100) ≈ 2.7e43, so Ψ = (c/2)(eˣ − 1), P and the 9×9
/// tangent (which carries eˣ·|F S₀|²/c) stay ~1e45·Y or less, far below DBL_MAX ≈ 1.8e308 even after
/// squaring in a solver's norms. With c = Y_t/4, x = 100 is a tangential Green strain of 5 (stretch ≈ 3.3):
/// no tissue state, only a diverging Newton step, gets there.
inline constexpr double kFungExponentCap = 100.0;

/// Parameters of the orthotropic StVK–Fung skin material at one point (SFLSH §3, docs/physics.md §1.2).
struct SkinMaterial {
  double young_tangent = 0.0;  ///< Y_t [Pa]: Young modulus in the tangent plane (⊥ n), isotropic in that plane
  double young_normal = 0.0;   ///< Y_n [Pa]: Young modulus along the through-thickness normal n
  double poisson = 0.2;        ///< ν ∈ (−1, ½); SFLSH uses 0.2 everywhere
  double saturation = 4.0;     ///< s > 0, dimensionless Fung saturation; SFLSH uses 4 everywhere
  FungScale fung_scale = FungScale::kTangentOverSaturation;
  ExponentOverflow overflow = ExponentOverflow::kThrow;
};

/// The names that validate() uses in its messages (the CLI passes its option names).
struct SkinMaterialNames {
  std::string_view young_tangent = "young_tangent";
  std::string_view young_normal = "young_normal";
  std::string_view poisson = "poisson";
  std::string_view saturation = "saturation";
};

/// Throws sflsh::Error naming the first bad field: Y_t, Y_n not finite positive, ν ∉ (−1, ½),
/// s not finite positive. These are exactly the conditions under which the small-strain stiffness
/// is positive definite (Li & Barbič 2014) and c is a positive number.
void validate(const SkinMaterial& material, const SkinMaterialNames& names = {});

/// μ₀ = 1/(2(1+ν)): the shear modulus of the unit-Young isotropic material (docs/physics.md §1.2).
double unit_lame_mu(double poisson);
/// λ₀ = ν/((1+ν)(1−2ν)): the first Lamé parameter of the unit-Young isotropic material (docs/physics.md §1.2).
double unit_lame_lambda(double poisson);

/// The Fung scale c [Pa] under material.fung_scale; +∞ for FungScale::kNone.
double fung_scale_c(const SkinMaterial& material);

/// The engineering constants of the linearized (small-strain) material in the frame (t₁, t₂, n), axis 3 = n,
/// and the Fung c: the parameters of FEBio's "Fung-ortho-compressible" material
/// (FEBioMech/FEFungOrthoCompressible.cpp, W = ½c(e^Q − 1) + ½K(ln J)², cQ = E:ℂ:E) that reproduce our Ψ.
///   E₁ = E₂ = Y_t, E₃ = Y_n,
///   ν_ij = ν √(E_i/E_j)  (FEBio's convention: compliance entry S_ij = −ν_ij/E_i), so ν₁₂ = ν,
///        ν₂₃ = ν √(Y_t/Y_n), ν₃₁ = ν √(Y_n/Y_t),
///   G_ij = √(E_i E_j) / (2(1+ν)), so G₁₂ = Y_t/(2(1+ν)), G₂₃ = G₃₁ = √(Y_t Y_n)/(2(1+ν)),
///   c = fung_scale_c(material).
/// FEBio adds ½K(ln J)², which our energy lacks, and FEBio requires K > 0: use a K that is small against
/// Y_t (e.g. 1e-6·Y_t) and expect a relative difference of order K/Y_t. mat_axis must put a₃ along n.
/// (FEBio's "Fung orthotropic" without "-compressible" is the uncoupled, J^{-1/3}-deviatoric variant and
/// differs at finite strain.) docs/material.md gives a worked example.
struct OrthotropicConstants {
  double E1 = 0, E2 = 0, E3 = 0;        ///< Young moduli [Pa]
  double G12 = 0, G23 = 0, G31 = 0;     ///< shear moduli [Pa]
  double nu12 = 0, nu23 = 0, nu31 = 0;  ///< Poisson ratios (S_ij = −ν_ij/E_i)
  double c = 0;                         ///< Fung scale [Pa] (+∞ when the Fung factor is off)
};
OrthotropicConstants small_strain_constants(const SkinMaterial& material);

}  // namespace sflsh::material
