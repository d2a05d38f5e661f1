// One linear tet: F, B = dF/dq, energy/forces/stiffness by finite differences, conservation laws, rigid
// invariance and the PSD projections.
#include "error_of.hpp"
#include "finite_difference.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/material/tet_element.hpp>

#include <Eigen/Eigenvalues>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sflsh {

using namespace sflsh::material;
using sflsh::testing::random_rotation;
using sflsh::testing::relative_error;

namespace {

TetNodes rest_nodes() {
  TetNodes X;                      // an irregular, positively oriented tet of ~2 cm edges [m]
  X << 0.00, 0.021, 0.004, 0.003,  //
      0.00, 0.002, 0.018, 0.005,   //
      0.00, 0.001, 0.003, 0.016;
  return X;
}

Vector12d flat(const TetNodes& x) { return Eigen::Map<const Vector12d>(x.data()); }
TetNodes nodes(const Vector12d& q) { return Eigen::Map<const TetNodes>(q.data()); }

OrthotropicFung skin_fung(const Eigen::Vector3d& n = Eigen::Vector3d(0.2, 0.3, 0.9).normalized()) {
  SkinMaterial sm;
  sm.young_tangent = 5000.0;
  sm.young_normal = 2000.0;
  return make_orthotropic_fung(sm, n);
}

/// A deformed state: x = A X + b with a random A of the given singular values, plus a non-affine wiggle
/// (irrelevant for a linear tet, but it makes the nodes arbitrary).
TetNodes deformed(const TetNodes& X, const Eigen::Vector3d& singular_values, std::mt19937& rng) {
  const Eigen::Matrix3d A = random_rotation(rng) * singular_values.asDiagonal() * random_rotation(rng).transpose();
  TetNodes x = A * X;
  x.colwise() += Eigen::Vector3d(0.1, -0.2, 0.05);
  return x;
}

}  // namespace

TEST(TetElement, DeformationGradientOfAnAffineMapIsItsMatrix) {
  const TetNodes X = rest_nodes();
  const TetRest rest = make_tet_rest(X);
  const Eigen::Matrix3d dm = X.rightCols<3>().colwise() - X.col(0);
  EXPECT_NEAR(rest.volume, dm.determinant() / 6.0, 1e-20);
  Eigen::Matrix3d A;
  A << 1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.2;
  TetNodes x = A * X;
  x.colwise() += Eigen::Vector3d(1.0, 2.0, 3.0);
  // D_m⁻¹ of 2 cm edges is ~50/m; the product rounds at ~1e-15 of A's entries.
  EXPECT_LT((tet_deformation_gradient(rest, x) - A).cwiseAbs().maxCoeff(), 1e-13);
  // vec(F) is linear in q with matrix B: vec(F(q)) = B q exactly (translations cancel in D_s).
  const Eigen::Matrix3d F = tet_deformation_gradient(rest, x);
  EXPECT_LT((tet_dF_dq(rest) * flat(x) - Eigen::Map<const Vector9d>(F.data())).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(TetElement, StiffnessIsTheDensePullBackOfTheStressDerivative) {
  // tet_elastic_dq2 forms V Bᵀ (∂P/∂F) B from B's sparsity (w_a(j) blocks) instead of the dense product; both
  // are the same sums reordered, so they agree to round-off (~1e-16 of ‖K‖; bound 1e-13), for every projection.
  const TetNodes X = rest_nodes();
  const TetRest rest = make_tet_rest(X);
  const OrthotropicFung m = skin_fung();
  const Matrix9x12d B = tet_dF_dq(rest);
  std::mt19937 rng(7);
  for (const Eigen::Vector3d& sv : {Eigen::Vector3d(1.3, 1.1, 0.95), Eigen::Vector3d(0.6, 0.8, 0.7)}) {
    const TetNodes x = deformed(X, sv, rng);
    const Matrix9d H = d2psi_ortho_fung_dF2(tet_deformation_gradient(rest, x), m);
    const Matrix12d dense = rest.volume * (B.transpose() * H * B);
    const Matrix12d dense_projected_stress = rest.volume * (B.transpose() * project_psd(H) * B);
    const double scale = dense.norm();
    EXPECT_LT((tet_elastic_dq2(rest, x, m, HessianProjection::kNone) - dense).norm(), 1e-13 * scale);
    EXPECT_LT((tet_elastic_dq2(rest, x, m, HessianProjection::kStressDerivative) - dense_projected_stress).norm(),
              1e-13 * scale);
    EXPECT_LT((tet_elastic_dq2(rest, x, m, HessianProjection::kElement) - project_psd(dense)).norm(), 1e-12 * scale);
  }
}

TEST(TetElement, RestStateHasNoEnergyNoForces) {
  const TetRest rest = make_tet_rest(rest_nodes());
  EXPECT_NEAR(tet_elastic_energy(rest, rest_nodes(), skin_fung()), 0.0, 1e-25);
  // F = I up to ~1e-15, so P ~ 1e-15·Y and f ~ P·area ~ 1e-15·5000·4e-4 N: bound 1e-12 N.
  EXPECT_LT(tet_elastic_forces(rest, rest_nodes(), skin_fung()).cwiseAbs().maxCoeff(), 1e-12);
}

// h = 1e-8 m on node positions of ~2e-2 m (strain steps 5e-7, as in the constitutive tests' 1e-6 steps),
// same truncation/rounding budget: 1e-6 relative.
TEST(TetElement, ForcesAndStiffnessMatchFiniteDifferences) {
  const TetNodes X = rest_nodes();
  const TetRest rest = make_tet_rest(X);
  const OrthotropicFung m = skin_fung();
  std::mt19937 rng(21);
  for (const Eigen::Vector3d& sv : {Eigen::Vector3d(1.3, 1.1, 0.95), Eigen::Vector3d(0.7, 0.8, 0.6),
                                    Eigen::Vector3d(1.0, 1.05, 0.08), Eigen::Vector3d(1.0, 0.9, -0.2)}) {
    const TetNodes x = deformed(X, sv, rng);
    const auto energy = [&](const Vector12d& q) { return tet_elastic_energy(rest, nodes(q), m); };
    const auto gradient = [&](const Vector12d& q) -> Vector12d { return tet_elastic_dq(rest, nodes(q), m); };
    const Vector12d g = gradient(flat(x));
    const Matrix12d K = tet_elastic_dq2(rest, x, m);
    EXPECT_LT(relative_error(sflsh::testing::central_gradient<12>(energy, flat(x), 1e-8), g), 1e-6) << sv.transpose();
    EXPECT_LT(relative_error(sflsh::testing::central_jacobian<12, 12>(gradient, flat(x), 1e-8), K), 1e-6)
        << sv.transpose();
    EXPECT_LT(sflsh::testing::asymmetry(K), 1e-13);
    EXPECT_EQ(tet_elastic_forces(rest, x, m), -g);
    // One evaluation gives the same numbers as the separate calls.
    const TetElastic all = tet_elastic(rest, x, m, true);
    EXPECT_DOUBLE_EQ(all.energy, tet_elastic_energy(rest, x, m));
    EXPECT_EQ(all.gradient, g);
    EXPECT_EQ(all.hessian, K);
  }
}

// Translation invariance ⇒ Σ f = 0; rotation invariance ⇒ Σ x × f = 0 (P Fᵀ symmetric). Both are sums of
// terms of size max|f| that cancel exactly in exact arithmetic: 1e-12 relative to max|f|.
TEST(TetElement, ForcesConserveMomentumAndAngularMomentum) {
  const TetNodes X = rest_nodes();
  const TetRest rest = make_tet_rest(X);
  std::mt19937 rng(22);
  for (int k = 0; k < 5; ++k) {
    const TetNodes x = deformed(X, Eigen::Vector3d(1.2, 0.9, 1.05 + 0.1 * k), rng);
    const Vector12d f = tet_elastic_forces(rest, x, skin_fung());
    const TetNodes fn = nodes(f);
    const double scale = f.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_LT(fn.rowwise().sum().cwiseAbs().maxCoeff(), 1e-12 * scale);
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) torque += x.col(a).cross(fn.col(a));
    EXPECT_LT(torque.cwiseAbs().maxCoeff(), 1e-12 * scale * x.cwiseAbs().maxCoeff());
    // The stiffness has the three translations in its null space.
    const Matrix12d K = tet_elastic_dq2(rest, x, skin_fung());
    for (int axis = 0; axis < 3; ++axis) {
      Vector12d t = Vector12d::Zero();
      for (int a = 0; a < 4; ++a) t(3 * a + axis) = 1.0;
      EXPECT_LT((K * t).cwiseAbs().maxCoeff(), 1e-12 * K.cwiseAbs().maxCoeff() * 4.0);
    }
  }
}

// x → R x + t leaves the energy unchanged and rotates the forces (1e-12 relative: rounding).
TEST(TetElement, RigidMotionInvariance) {
  const TetNodes X = rest_nodes();
  const TetRest rest = make_tet_rest(X);
  std::mt19937 rng(23);
  const TetNodes x = deformed(X, Eigen::Vector3d(1.25, 0.85, 1.1), rng);
  const double energy = tet_elastic_energy(rest, x, skin_fung());
  const TetNodes f = nodes(tet_elastic_forces(rest, x, skin_fung()));
  for (int k = 0; k < 5; ++k) {
    const Eigen::Matrix3d R = random_rotation(rng);
    TetNodes y = R * x;
    y.colwise() += Eigen::Vector3d(0.3 * k, -1.0, 2.0);
    EXPECT_NEAR(tet_elastic_energy(rest, y, skin_fung()), energy, 1e-12 * energy);
    EXPECT_LT(relative_error(nodes(tet_elastic_forces(rest, y, skin_fung())), TetNodes(R * f)), 1e-12);
  }
  // A rigidly moved rest tet stores nothing.
  TetNodes moved = random_rotation(rng) * X;
  moved.colwise() += Eigen::Vector3d(5.0, 5.0, 5.0);
  EXPECT_LT(tet_elastic_energy(rest, moved, skin_fung()), 1e-20);
}

TEST(TetElement, ProjectedStiffnessIsPsd) {
  const TetNodes X = rest_nodes();
  const TetRest rest = make_tet_rest(X);
  std::mt19937 rng(24);
  const TetNodes x = deformed(X, Eigen::Vector3d(0.5, 0.6, 0.9), rng);  // compressed: StVK is indefinite
  const Matrix12d K = tet_elastic_dq2(rest, x, skin_fung());
  const double scale = K.cwiseAbs().maxCoeff();
  ASSERT_LT(Eigen::SelfAdjointEigenSolver<Matrix12d>(K).eigenvalues().minCoeff(), -1e-6 * scale);
  for (HessianProjection p : {HessianProjection::kStressDerivative, HessianProjection::kElement}) {
    const Matrix12d Kp = tet_elastic_dq2(rest, x, skin_fung(), p);
    // Rounding of V Bᵀ H₊ B (or of the 12×12 reconstruction): −1e-12 of the largest entry.
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Matrix12d>(Kp).eigenvalues().minCoeff(), -1e-12 * scale);
    EXPECT_EQ(tet_elastic(rest, x, skin_fung(), true, p).hessian, Kp);
  }
  // In tension the exact stiffness is already PSD and the 9×9 projection leaves it as it is.
  const TetNodes stretched = deformed(X, Eigen::Vector3d(1.2, 1.1, 1.05), rng);
  EXPECT_EQ(tet_elastic_dq2(rest, stretched, skin_fung(), HessianProjection::kStressDerivative),
            tet_elastic_dq2(rest, stretched, skin_fung()));
}

TEST(TetElement, RejectsInvertedAndDegenerateRestTets) {
  TetNodes X = rest_nodes();
  X.col(1).swap(X.col(2));  // nodes 1 and 2 exchanged: negative orientation
  EXPECT_THAT(sflsh::testing::error_of([&] { make_tet_rest(X); }), ::testing::HasSubstr("inverted"));
  TetNodes flat_tet = rest_nodes();
  flat_tet.row(2) << 0.0, 0.0, 0.0, 1e-16;  // node 3 a hair above the plane z = 0 of the others
  EXPECT_THAT(sflsh::testing::error_of([&] { make_tet_rest(flat_tet); }), ::testing::HasSubstr("degenerate"));
  TetNodes nan = rest_nodes();
  nan(0, 0) = std::nan("");
  EXPECT_THROW(make_tet_rest(nan), Error);
}

}  // namespace sflsh
