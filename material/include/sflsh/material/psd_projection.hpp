#pragma once
// Projection of symmetric element matrices onto the positive semi-definite cone by eigenvalue
// clamping (docs/physics.md §1.2 [P]): A = V Λ Vᵀ ↦ V max(Λ, 0) Vᵀ, the nearest PSD matrix in the
// Frobenius norm. StVK-type energies are indefinite in compression; Newton needs a PSD Hessian.
// Fixed sizes only (Eigen's SelfAdjointEigenSolver on fixed-size matrices does not allocate).
#include <Eigen/Core>

namespace sflsh::material {

using Matrix12d = Eigen::Matrix<double, 12, 12>;

/// Where a tet's stiffness is made PSD (see tet_element.hpp).
enum class HessianProjection {
  kNone,              ///< the exact Hessian (may be indefinite)
  kStressDerivative,  ///< project the 9×9 dP/dF, then K = V Bᵀ [dP/dF]₊ B (what Newton should use)
  kElement,           ///< project the 12×12 K itself
};

/// The nearest PSD matrix to sym(A) = ½(A + Aᵀ). A matrix whose eigenvalues are all ≥ 0 is returned
/// unchanged (bit for bit), so projecting a PSD Hessian costs one eigen-decomposition and changes nothing.
Eigen::Matrix<double, 9, 9> project_psd(const Eigen::Matrix<double, 9, 9>& A);
Matrix12d project_psd(const Matrix12d& A);

}  // namespace sflsh::material
