#include <sflsh/core/error.hpp>
#include <sflsh/material/tet_element.hpp>

#include <Eigen/LU>

#include <algorithm>

namespace sflsh::material {

namespace {

Eigen::Matrix3d edge_matrix(const TetNodes& x) {
  Eigen::Matrix3d d;
  d << x.col(1) - x.col(0), x.col(2) - x.col(0), x.col(3) - x.col(0);  // [x₁−x₀, x₂−x₀, x₃−x₀]
  return d;
}

/// V Bᵀ vec(P) without forming B: node a gets V P w_aᵀ (w_a as in tet_dF_dq).
Vector12d gradient_from(const TetRest& rest, const Eigen::Matrix3d& P) {
  const Eigen::Matrix3d G = rest.volume * P * rest.dm_inv.transpose();  // columns: nodes 1..3 (docs/physics.md §1.2)
  Vector12d g;
  g.segment<3>(3) = G.col(0);
  g.segment<3>(6) = G.col(1);
  g.segment<3>(9) = G.col(2);
  g.segment<3>(0) = -(G.col(0) + G.col(1) + G.col(2));
  return g;
}

/// V Bᵀ H B without forming B (B = tet_dF_dq, H = ∂²Ψ/∂F² in vec order i + 3j): B's only entries are
/// ∂F_ij/∂(x_a)_i = w_a(j), so (H B) column 3b + k is Σ_l w_b(l) H(:, k + 3l) and row 3a + i of Bᵀ(HB) is
/// Σ_j w_a(j) (HB)(i + 3j, :). About 750 multiplications against the dense product's 2,300 plus its packing:
/// the element Hessian is the full-space assembly's largest cost (docs/decisions.md "Element Hessian").
Matrix12d pull_back(const TetRest& rest, const Matrix9d& H) {
  Eigen::Matrix<double, 4, 3> w;
  w.bottomRows<3>() = rest.dm_inv;
  w.row(0) = -rest.dm_inv.colwise().sum();
  Matrix9x12d HB;
  for (int b = 0; b < 4; ++b)
    for (int k = 0; k < 3; ++k)
      HB.col(3 * b + k) = w(b, 0) * H.col(k) + w(b, 1) * H.col(k + 3) + w(b, 2) * H.col(k + 6);
  Matrix12d K;
  for (int a = 0; a < 4; ++a) {
    K.middleRows<3>(3 * a) = (rest.volume * w(a, 0)) * HB.topRows<3>() + (rest.volume * w(a, 1)) * HB.middleRows<3>(3) +
                             (rest.volume * w(a, 2)) * HB.bottomRows<3>();
  }
  return K;
}

Matrix12d hessian_from(const TetRest& rest, const Matrix9d& dPdF, HessianProjection projection) {
  if (projection == HessianProjection::kStressDerivative) return pull_back(rest, project_psd(dPdF));
  Matrix12d K = pull_back(rest, dPdF);  // K = V Bᵀ (dP/dF) B
  if (projection == HessianProjection::kElement) K = project_psd(K);
  return K;
}

}  // namespace

TetRest make_tet_rest(const TetNodes& rest) {
  require(rest.allFinite(), "tet: non-finite rest node positions");
  const Eigen::Matrix3d dm = edge_matrix(rest);
  double longest = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (rest.col(a) - rest.col(b)).norm());
  const double det = dm.determinant();
  require(det > 0.0, "tet: the rest tet is inverted or flat (det D_m = {:.3g}); nodes must be positively oriented",
          det);
  require(det > 1e-12 * longest * longest * longest,
          "tet: the rest tet is degenerate (det D_m = {:.3g} for a longest edge of {:.3g} m)", det, longest);
  TetRest r;
  r.dm_inv = dm.inverse();
  r.volume = det / 6.0;
  return r;
}

Eigen::Matrix3d tet_deformation_gradient(const TetRest& rest, const TetNodes& x) {
  return edge_matrix(x) * rest.dm_inv;  // F = D_s D_m⁻¹ (docs/physics.md §1.2)
}

Matrix9x12d tet_dF_dq(const TetRest& rest) {
  // F_ij = Σ_k (x_{k+1} − x₀)_i (D_m⁻¹)_kj, so ∂F_ij/∂(x_a)_i = w_a(j).
  Eigen::Matrix<double, 4, 3> w;
  w.bottomRows<3>() = rest.dm_inv;
  w.row(0) = -rest.dm_inv.colwise().sum();
  Matrix9x12d B = Matrix9x12d::Zero();
  for (int a = 0; a < 4; ++a)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) B(i + 3 * j, 3 * a + i) = w(a, j);
  return B;
}

double tet_elastic_energy(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material) {
  return rest.volume * psi_ortho_fung(tet_deformation_gradient(rest, x), material);
}

Vector12d tet_elastic_dq(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material) {
  return gradient_from(rest, dpsi_ortho_fung_dF(tet_deformation_gradient(rest, x), material));
}

Vector12d tet_elastic_forces(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material) {
  return -tet_elastic_dq(rest, x, material);
}

Matrix12d tet_elastic_dq2(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material,
                          HessianProjection projection) {
  return hessian_from(rest, d2psi_ortho_fung_dF2(tet_deformation_gradient(rest, x), material), projection);
}

TetElastic tet_elastic(const TetRest& rest, const TetNodes& x, const OrthotropicFung& material, bool with_hessian,
                       HessianProjection projection) {
  const OrthoFungValues v = eval_ortho_fung(tet_deformation_gradient(rest, x), material, with_hessian);
  TetElastic e;
  e.energy = rest.volume * v.psi;
  e.gradient = gradient_from(rest, v.P);
  if (with_hessian) e.hessian = hessian_from(rest, v.dPdF, projection);
  return e;
}

}  // namespace sflsh::material
