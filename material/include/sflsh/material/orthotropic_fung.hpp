#pragma once
// Orthotropic Saint Venant–Kirchhoff with Fung-type saturation: energy density, first Piola–Kirchhoff
// stress and its derivative (SFLSH §3 after Romero et al. 2020; the formulas are docs/physics.md §1.2).
//
// Flatten order (used by every 9-vector and 9×9 matrix of sflsh::material): vec(F) is column-major,
// entry i + 3j holds F(i, j), i.e. vec(F) = [F₀₀ F₁₀ F₂₀ F₀₁ F₁₁ F₂₁ F₀₂ F₁₂ F₂₂]ᵀ — Eigen's own storage
// order of Matrix3d, so Eigen::Map<const Vector9d>(F.data()) is vec(F).
//
//   E  = ½(FᵀF − I)                                           Green–Lagrange strain
//   P_Y = Y_t^{1/4} (I − n nᵀ) + Y_n^{1/4} n nᵀ,  Ê = P_Y E P_Y   stiffness scaling (Li & Barbič 2014)
//   Ψ₀ = μ₀ tr(Ê²) + (λ₀/2)(tr Ê)²,  μ₀ = 1/(2(1+ν)), λ₀ = ν/((1+ν)(1−2ν))
//   Ψ  = (c/2)(exp(2Ψ₀/c) − 1),  c = Y_t / s (FungScale)        Fung saturation (FEBio's form)
//
// Everything here works on fixed-size Eigen types and never allocates; it is safe to call from
// several threads at once. Non-finite F and Fung exponents above kFungExponentCap throw sflsh::Error
// (or, with ExponentOverflow::kContinueLinearly, continue finitely): no NaN or Inf comes out silently.
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Core>

namespace sflsh::material {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;

/// The per-point constants of the energy, precomputed once (validation and fourth roots are not free).
struct OrthotropicFung {
  Eigen::Matrix3d scaling = Eigen::Matrix3d::Identity();  ///< P_Y (symmetric) [Pa^{1/4}]
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();      ///< n, unit, in rest (unposed) coordinates
  double mu0 = 0.0;                                       ///< μ₀ (dimensionless)
  double lambda0 = 0.0;                                   ///< λ₀ (dimensionless)
  double c = 0.0;                                         ///< Fung scale [Pa]; +∞ when off
  double inv_c = 0.0;                                     ///< 1/c [1/Pa]; 0 when the Fung factor is off
  ExponentOverflow overflow = ExponentOverflow::kThrow;
};

/// Validates `material` (see validate()) and the normal (finite, |n| within 1e-6 of 1, then normalized).
/// @param[in] material  Y_t, Y_n [Pa], ν, s and the Fung options
/// @param[in] normal    through-thickness direction n in rest coordinates (the transverse-isotropy axis)
OrthotropicFung make_orthotropic_fung(const SkinMaterial& material, const Eigen::Vector3d& normal);

/// Green–Lagrange strain E = ½(FᵀF − I).
Eigen::Matrix3d green_strain(const Eigen::Matrix3d& F);

/// The orthotropic StVK part alone (docs/physics.md §1.2):
/// \f[ \Psi_0 = \mu_0\,\mathrm{tr}(\hat E^2) + \tfrac{\lambda_0}{2}(\mathrm{tr}\,\hat E)^2,\quad \hat E = P_Y E P_Y \f]
double psi_ortho_stvk(const Eigen::Matrix3d& F, const OrthotropicFung& m);
/// \f[ \partial\Psi_0/\partial F = F S_0,\quad S_0 = P_Y(2\mu_0\hat E + \lambda_0\,\mathrm{tr}(\hat E) I)P_Y \f] [Pa]
Eigen::Matrix3d dpsi_ortho_stvk_dF(const Eigen::Matrix3d& F, const OrthotropicFung& m);
/// ∂²Ψ₀/∂F² (9×9, vec order above): dP₀ = dF S₀ + F P_Y(2μ₀ dÊ + λ₀ tr(dÊ) I)P_Y, dÊ = P_Y sym(FᵀdF) P_Y.
Matrix9d d2psi_ortho_stvk_dF2(const Eigen::Matrix3d& F, const OrthotropicFung& m);

/// The Fung exponent x = 2Ψ₀/c (0 when the Fung factor is off). Solvers can use it to reject a trial
/// state before evaluating (x > kFungExponentCap throws under ExponentOverflow::kThrow).
double fung_exponent(const Eigen::Matrix3d& F, const OrthotropicFung& m);

/// The full energy density [J/m³] (docs/physics.md §1.2, FEBio's W = ½c(e^Q − 1) with Q = 2Ψ₀/c):
/// \f[ \Psi = \tfrac{c}{2}\left(e^{2\Psi_0/c} - 1\right) \f]
/// evaluated with expm1 so that Ψ → Ψ₀ keeps full precision at small strain.
double psi_ortho_fung(const Eigen::Matrix3d& F, const OrthotropicFung& m);
/// First Piola–Kirchhoff stress [Pa]: \f[ P = \partial\Psi/\partial F = g\,F S_0,\quad g = e^{2\Psi_0/c} \f]
Eigen::Matrix3d dpsi_ortho_fung_dF(const Eigen::Matrix3d& F, const OrthotropicFung& m);
/// dP/dF [Pa] (9×9, symmetric, vec order above):
/// \f[ \partial^2\Psi/\partial F^2 = g\,\partial^2\Psi_0/\partial F^2 +
/// \tfrac{2g}{c}\,\mathrm{vec}(FS_0)\,\mathrm{vec}(FS_0)^T \f] — the same as docs/physics.md's dS = g[ℂ₀:dE +
/// (2/c)(S₀:dE)S₀] since S₀:sym(FᵀdF) = (F S₀):dF.
Matrix9d d2psi_ortho_fung_dF2(const Eigen::Matrix3d& F, const OrthotropicFung& m);

/// Ψ, P and dP/dF from one evaluation of the shared terms (what an element needs).
struct OrthoFungValues {
  double psi = 0.0;
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  Matrix9d dPdF = Matrix9d::Zero();  ///< left zero unless requested
};
OrthoFungValues eval_ortho_fung(const Eigen::Matrix3d& F, const OrthotropicFung& m, bool with_hessian);

/// Cauchy stress σ = P Fᵀ / det F [Pa]; throws sflsh::Error when det F ≤ 0.
Eigen::Matrix3d cauchy_stress(const Eigen::Matrix3d& F, const Eigen::Matrix3d& P);

}  // namespace sflsh::material
