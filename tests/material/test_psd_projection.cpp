// Eigenvalue clamping of 9×9 and 12×12 symmetric matrices.
#include "finite_difference.hpp"

#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/material/psd_projection.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

using namespace sflsh::material;

namespace {

template <int N>
Eigen::Matrix<double, N, N> random_symmetric(std::mt19937& rng, double shift) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Matrix<double, N, N> A;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) A(i, j) = normal(rng);
  return 0.5 * (A + A.transpose()) + shift * Eigen::Matrix<double, N, N>::Identity();
}

template <int N>
void check_projection(std::mt19937& rng) {
  using Matrix = Eigen::Matrix<double, N, N>;
  for (int k = 0; k < 20; ++k) {
    const Matrix A = random_symmetric<N>(rng, 0.0);
    const Eigen::SelfAdjointEigenSolver<Matrix> before(A);
    ASSERT_LT(before.eigenvalues().minCoeff(), 0.0);  // the case under test really is indefinite
    const Matrix B = project_psd(A);
    const Eigen::SelfAdjointEigenSolver<Matrix> after(B);
    // Reconstruction V Λ₊ Vᵀ is exact up to ~N·ε·‖A‖ rounding: −1e-12·‖A‖ bounds "non-negative".
    const double scale = A.cwiseAbs().maxCoeff();
    EXPECT_GE(after.eigenvalues().minCoeff(), -1e-12 * scale);
    EXPECT_LT(sflsh::testing::asymmetry(B), 1e-13);
    // Nearest PSD matrix: ‖A − B‖²_F = Σ of the squared negative eigenvalues.
    const double removed = before.eigenvalues().cwiseMin(0.0).squaredNorm();
    EXPECT_NEAR((A - B).squaredNorm(), removed, 1e-10 * removed);
    // Positive eigenpairs are kept: B v = λ v.
    for (int i = 0; i < N; ++i) {
      if (before.eigenvalues()(i) > 1e-6) {
        EXPECT_LT((B * before.eigenvectors().col(i) - before.eigenvalues()(i) * before.eigenvectors().col(i)).norm(),
                  1e-12 * scale);
      }
    }
  }
  for (int k = 0; k < 5; ++k) {  // PSD in → the same matrix out, bit for bit
    const Matrix A = random_symmetric<N>(rng, 3.0 * N);
    ASSERT_GE(Eigen::SelfAdjointEigenSolver<Matrix>(A).eigenvalues().minCoeff(), 0.0);
    EXPECT_EQ(project_psd(A), A);
  }
  // A PSD Gram matrix with an exact null space (rank N−3) also passes through unchanged when its
  // computed eigenvalues are ≥ 0, or is touched only at rounding level otherwise.
  Eigen::Matrix<double, N, N - 3> G = Eigen::Matrix<double, N, N - 3>::Random();
  const Matrix A = G * G.transpose();
  EXPECT_LT((project_psd(A) - A).cwiseAbs().maxCoeff(), 1e-12 * A.cwiseAbs().maxCoeff());
}

}  // namespace

TEST(PsdProjection, ClampsNegativeEigenvalues9x9) {
  std::mt19937 rng(3);
  check_projection<9>(rng);
}

TEST(PsdProjection, ClampsNegativeEigenvalues12x12) {
  std::mt19937 rng(4);
  check_projection<12>(rng);
}

// Compression makes StVK's dP/dF indefinite; after projection it is PSD.
TEST(PsdProjection, MakesTheCompressedMaterialTangentPsd) {
  SkinMaterial sm;
  sm.young_tangent = 5000.0;
  sm.young_normal = 2000.0;
  const OrthotropicFung m = make_orthotropic_fung(sm, Eigen::Vector3d::UnitZ());
  const Eigen::Matrix3d F = Eigen::Vector3d(0.5, 0.6, 0.7).asDiagonal();
  const Matrix9d H = d2psi_ortho_fung_dF2(F, m);
  ASSERT_LT(Eigen::SelfAdjointEigenSolver<Matrix9d>(H).eigenvalues().minCoeff(), -1.0);  // [Pa]: clearly indefinite
  const Matrix9d Hp = project_psd(H);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Matrix9d>(Hp).eigenvalues().minCoeff(), -1e-12 * H.cwiseAbs().maxCoeff());
  // Stretching keeps the tangent PD here, and then projection changes nothing.
  const Matrix9d Hs = d2psi_ortho_fung_dF2(Eigen::Vector3d(1.2, 1.1, 1.05).asDiagonal(), m);
  ASSERT_GT(Eigen::SelfAdjointEigenSolver<Matrix9d>(Hs).eigenvalues().minCoeff(), 0.0);
  EXPECT_EQ(project_psd(Hs), Hs);
}
