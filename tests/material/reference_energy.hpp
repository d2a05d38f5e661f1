#pragma once
// An independent evaluation of the skin energy for the tests, written differently from the production
// code on purpose: the orthotropic stiffness is built from engineering constants (E_i, ν_ij, G_ij) by
// inverting a 6×6 Voigt compliance in an explicit material frame, instead of SFLSH/Li–Barbič's scaled
// strain Ê = P_Y E P_Y. Templated on the scalar so that complex-step differentiation gives P to machine
// precision: ∂Ψ/∂F_ij = Im Ψ(F + i h e_ij) / h with h = 1e-30 (no subtractive cancellation).
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <complex>
#include <limits>

namespace sflsh::testing {

/// The stiffness of the reference energy: a 6×6 Voigt matrix (order 11, 22, 33, 23, 31, 12, engineering
/// shears) in the frame [t₁ t₂ n], plus the frame and c.
struct ReferenceMaterial {
  Eigen::Matrix<double, 6, 6> stiffness;
  Eigen::Matrix3d frame;  ///< columns t₁, t₂, n
  double c = 0.0;         ///< +∞ when the Fung factor is off
};

inline ReferenceMaterial reference_material(const material::SkinMaterial& m, const Eigen::Vector3d& normal) {
  const double E[3] = {m.young_tangent, m.young_tangent, m.young_normal};
  const double nu = m.poisson;
  // ν_ij = ν √(E_i/E_j), G_ij = √(E_i E_j)/(2(1+ν)) (docs/physics.md §1.2, small-strain constants).
  auto nu_ij = [&](int i, int j) { return nu * std::sqrt(E[i] / E[j]); };
  auto g_ij = [&](int i, int j) { return std::sqrt(E[i] * E[j]) / (2.0 * (1.0 + nu)); };
  Eigen::Matrix<double, 6, 6> compliance = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 3; ++i) {
    compliance(i, i) = 1.0 / E[i];
    for (int j = 0; j < 3; ++j)
      if (i != j) compliance(i, j) = -nu_ij(i, j) / E[i];  // ε_j = −ν_ij σ_i / E_i
  }
  compliance(3, 3) = 1.0 / g_ij(1, 2);
  compliance(4, 4) = 1.0 / g_ij(2, 0);
  compliance(5, 5) = 1.0 / g_ij(0, 1);
  ReferenceMaterial r;
  r.stiffness = compliance.inverse();
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d t1 = (helper - helper.dot(n) * n).normalized();
  r.frame << t1, n.cross(t1), n;
  switch (m.fung_scale) {
    case material::FungScale::kTangentOverSaturation:
      r.c = m.young_tangent / m.saturation;
      break;
    case material::FungScale::kTangentTimesSaturation:
      r.c = m.young_tangent * m.saturation;
      break;
    case material::FungScale::kNone:
      r.c = std::numeric_limits<double>::infinity();
      break;
  }
  return r;
}

/// Ψ = (c/2)(exp(2W/c) − 1), W = ½ εᵀ ℂ ε with ε the Voigt vector of Rᵀ E R, E = ½(FᵀF − I).
template <typename T>
T reference_psi(const Eigen::Matrix<T, 3, 3>& F, const ReferenceMaterial& r) {
  const Eigen::Matrix<T, 3, 3> R = r.frame.cast<T>();
  const Eigen::Matrix<T, 3, 3> E = T(0.5) * (F.transpose() * F - Eigen::Matrix<T, 3, 3>::Identity());
  const Eigen::Matrix<T, 3, 3> El = R.transpose() * E * R;
  Eigen::Matrix<T, 6, 1> e;
  e << El(0, 0), El(1, 1), El(2, 2), T(2.0) * El(1, 2), T(2.0) * El(2, 0), T(2.0) * El(0, 1);
  const T w = T(0.5) * (e.transpose() * r.stiffness.cast<T>() * e)(0, 0);
  if (std::isinf(r.c)) return w;
  return T(0.5 * r.c) * (std::exp(T(2.0 / r.c) * w) - T(1.0));
}

/// P = ∂Ψ/∂F of the reference energy by complex step (exact to rounding).
inline Eigen::Matrix3d reference_piola(const Eigen::Matrix3d& F, const ReferenceMaterial& r) {
  using Complex = std::complex<double>;
  constexpr double h = 1e-30;
  Eigen::Matrix3d P;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Eigen::Matrix<Complex, 3, 3> Fc = F.cast<Complex>();
      Fc(i, j) += Complex(0.0, h);
      P(i, j) = reference_psi<Complex>(Fc, r).imag() / h;
    }
  return P;
}

}  // namespace sflsh::testing
