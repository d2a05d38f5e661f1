#pragma once
// One linear tetrahedron of the orthotropic StVK–Fung material: F = D_s D_m⁻¹ (docs/physics.md §1.2),
// energy V·Ψ(F), gradient V·Bᵀ vec(P), Hessian V·Bᵀ (dP/dF) B with B = ∂vec(F)/∂q (9×12), following
// Bartels' linear_tet_*_dq / _dq2 layering. Fixed sizes, no heap allocation.
//
// Conventions:
//  - Nodes are the columns of a 3×4 matrix, [x₀ x₁ x₂ x₃] [m]; q = [x₀; x₁; x₂; x₃] (12), node a, axis i at 3a + i.
//  - D_m = [X₁−X₀, X₂−X₀, X₃−X₀] at rest (positive orientation, det D_m > 0), D_s the same at x.
//  - vec(F) is column-major (orthotropic_fung.hpp).
//  - Sign: tet_elastic_dq is ∂(VΨ)/∂q; the internal elastic forces on the nodes are its negative,
//    f = −∂(VΨ)/∂q, so f_{1..3} = −V P D_m⁻ᵀ (columns) and f₀ = −(f₁ + f₂ + f₃) (docs/physics.md §1.2).
//
// PSD projection (psd_projection.hpp): HessianProjection::kStressDerivative clamps the eigenvalues of the
// 9×9 dP/dF and maps it, K₊ = V Bᵀ [dP/dF]₊ B. We prefer it to clamping the 12×12 K: (1) a 9×9
// eigen-decomposition costs ~40% of a 12×12 one; (2) B has full row rank for a non-degenerate tet, so
// K is PSD exactly when dP/dF is, and the result is PSD by construction; (3) the three rigid-translation
// null modes of K (B kills translations) stay exactly zero instead of picking up rounding noise;
// (4) the clamping does not depend on the shape of the tet. The price: K₊ is not the nearest PSD matrix
// to K in the 12×12 Frobenius norm (B is not orthonormal); kElement gives that one when wanted.
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/material/psd_projection.hpp>

#include <Eigen/Core>

namespace sflsh::material {

using Vector12d = Eigen::Matrix<double, 12, 1>;
using Matrix9x12d = Eigen::Matrix<double, 9, 12>;
using TetNodes = Eigen::Matrix<double, 3, 4>;

/// What a tet keeps from its rest shape.
struct TetRest {
  Eigen::Matrix3d dm_inv = Eigen::Matrix3d::Identity();  ///< D_m⁻¹ [1/m]
  double volume = 0.0;                                   ///< V = det(D_m)/6 [m³]
};

/// D_m⁻¹ and V of a rest tet. Throws sflsh::Error when the tet is inverted (det D_m ≤ 0) or degenerate
/// (det D_m ≤ 1e-12 · (longest edge)³, i.e. a shape far beyond any usable mesh quality).
/// @param[in] rest  3×4 rest (unposed) node positions [m], positively oriented
TetRest make_tet_rest(const TetNodes& rest);

/// F = D_s D_m⁻¹ (docs/physics.md §1.2).
Eigen::Matrix3d tet_deformation_gradient(const TetRest& rest, const TetNodes& x);

/// B = ∂vec(F)/∂q (9×12), constant per tet: B(i + 3j, 3a + i) = w_a(j), w_a = row a−1 of D_m⁻¹ for
/// a = 1..3 and w₀ = −(w₁ + w₂ + w₃).
Matrix9x12d tet_dF_dq(const TetRest& rest);

/// Element energy V·Ψ(F) [J].
double tet_elastic_energy(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material);
/// ∂(VΨ)/∂q = V Bᵀ vec(P) [N] (12).
Vector12d tet_elastic_dq(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material);
/// Internal elastic nodal forces f = −∂(VΨ)/∂q [N] (12); they sum to zero per axis.
Vector12d tet_elastic_forces(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material);
/// Stiffness K = ∂²(VΨ)/∂q² = V Bᵀ (dP/dF) B [N/m] (12×12), optionally projected to PSD.
Matrix12d tet_elastic_dq2(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material,
                          HessianProjection projection = HessianProjection::kNone);

/// Energy, gradient and Hessian from one constitutive evaluation (what an assembly loop calls).
struct TetElastic {
  double energy = 0.0;                     ///< V·Ψ [J]
  Vector12d gradient = Vector12d::Zero();  ///< ∂(VΨ)/∂q [N] (= −forces)
  Matrix12d hessian = Matrix12d::Zero();   ///< ∂²(VΨ)/∂q² [N/m]; zero unless requested
};
TetElastic tet_elastic(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material, bool with_hessian,
                       HessianProjection projection = HessianProjection::kNone);

}  // namespace sflsh::material
