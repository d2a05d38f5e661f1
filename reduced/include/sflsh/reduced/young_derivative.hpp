#pragma once
// The derivative of the orthotropic StVK–Fung stress with respect to the two Young moduli of a point, at a
// fixed deformation gradient (docs/physics.md §1.2, orthotropic_fung.hpp): what the forward sensitivities of the
// reduced model need for ∂(ω V ∂Ψ/∂q)/∂Y (reduced_sensitivity.hpp).
//
//   P = φ'(x) F S₀,  x = 2Ψ₀/c,  S₀ = P_Y M P_Y,  M = 2μ₀Ê + λ₀ tr(Ê) I,  Ê = P_Y E P_Y,
//   P_Y = Y_t^{1/4}(I − nnᵀ) + Y_n^{1/4} nnᵀ,  c = Y_t/s or s·Y_t (FungScale): ∂c/∂Y_t = c/Y_t, ∂c/∂Y_n = 0.
// For one modulus Y with D = ∂P_Y/∂Y (¼Y_t^{−3/4}(I − nnᵀ) for Y_t, ¼Y_n^{−3/4} nnᵀ for Y_n):
//   ∂Ê  = D E P_Y + P_Y E D,      ∂Ψ₀ = M : ∂Ê,
//   ∂S₀ = D M P_Y + P_Y M D + P_Y (2μ₀ ∂Ê + λ₀ tr(∂Ê) I) P_Y,
//   ∂x  = 2 ∂Ψ₀/c − x ∂c/c,       ∂P  = φ''(x) ∂x F S₀ + φ'(x) F ∂S₀,
// with φ(x) = eˣ − 1 (φ' = φ'' = eˣ), continued linearly beyond kFungExponentCap under
// ExponentOverflow::kContinueLinearly (φ' = e^cap, φ'' = 0), and φ' = 1, φ'' = 0 when the Fung factor is off.
#include <sflsh/material/orthotropic_fung.hpp>

#include <Eigen/Core>

namespace sflsh::reduced {

/// ∂P/∂Y_t and ∂P/∂Y_n at fixed F [dimensionless: Pa per Pa].
struct YoungStressDerivative {
  Eigen::Matrix3d tangent = Eigen::Matrix3d::Zero();  ///< ∂P/∂Y_t
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();   ///< ∂P/∂Y_n
};

/// The moduli (Y_t, Y_n) [Pa] a material was made with, read back from P_Y (eigenvalue Y_t^{1/4} on the tangent
/// plane, Y_n^{1/4} along n).
Eigen::Vector2d young_moduli(const material::OrthotropicFung& m);

/// \f[ \partial P/\partial Y_t,\ \partial P/\partial Y_n \f] at F (formulas above). Throws sflsh::Error where
/// dpsi_ortho_fung_dF would (non-finite F, a Fung exponent over the cap under ExponentOverflow::kThrow).
YoungStressDerivative d2psi_ortho_fung_dF_dyoung(const Eigen::Matrix3d& F, const material::OrthotropicFung& m);

}  // namespace sflsh::reduced
