#include <sflsh/material/psd_projection.hpp>

#include <Eigen/Eigenvalues>

namespace sflsh::material {

namespace {

template <int N>
Eigen::Matrix<double, N, N> project_psd_fixed(const Eigen::Matrix<double, N, N>& A) {
  using Matrix = Eigen::Matrix<double, N, N>;
  const Matrix sym = 0.5 * (A + A.transpose());
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(sym);  // fixed size: no heap allocation
  const auto& lambda = eig.eigenvalues();
  if (lambda.minCoeff() >= 0.0) return A;  // already PSD: unchanged
  // V max(Λ, 0) Vᵀ (docs/physics.md §1.2 [P]: eigenvalue clamping)
  const Eigen::Matrix<double, N, 1> clamped = lambda.cwiseMax(0.0);
  return eig.eigenvectors() * clamped.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace

Eigen::Matrix<double, 9, 9> project_psd(const Eigen::Matrix<double, 9, 9>& A) { return project_psd_fixed<9>(A); }

Matrix12d project_psd(const Matrix12d& A) { return project_psd_fixed<12>(A); }

}  // namespace sflsh::material
