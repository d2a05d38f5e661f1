// Orthotropic StVK with Fung saturation (docs/physics.md §1.2). The derivation, step by step:
//
//   Ψ₀(F) = μ₀ Ê:Ê + (λ₀/2)(tr Ê)²,   Ê = P_Y E P_Y,   E = ½(FᵀF − I)
//   dΨ₀   = (2μ₀ Ê + λ₀ tr(Ê) I) : dÊ = S₀ : dE          (P_Y symmetric, so A:P_Y dE P_Y = P_Y A P_Y : dE)
//   dE    = sym(Fᵀ dF),  S₀ symmetric  ⇒  S₀ : dE = (F S₀) : dF,  so P₀ = ∂Ψ₀/∂F = F S₀
//   dP₀   = dF S₀ + F dS₀,  dS₀ = P_Y (2μ₀ dÊ + λ₀ tr(dÊ) I) P_Y,  dÊ = P_Y dE P_Y
//
//   Ψ = (c/2) φ(x),  x = 2Ψ₀/c,  φ(x) = eˣ − 1 (up to the cap; see overflow below)
//   ∂Ψ/∂F   = φ'(x) P₀                                   (c/2 · φ' · 2/c = φ')
//   ∂²Ψ/∂F² = φ'(x) ∂P₀/∂F + (2/c) φ''(x) vec(P₀) vec(P₀)ᵀ
//
// Overflow: beyond x_cap = kFungExponentCap either throw, or continue φ by its tangent,
// φ(x) = e^{x_cap}(1 + x − x_cap) − 1, φ' = e^{x_cap}, φ'' = 0 (C¹ and consistent derivatives).
#include <sflsh/core/error.hpp>
#include <sflsh/material/fung_strain.hpp>
#include <sflsh/material/orthotropic_fung.hpp>

#include <Eigen/LU>

#include <cmath>

namespace sflsh::material {

namespace {

/// The shared intermediate quantities of one evaluation.
struct Strain {
  Eigen::Matrix3d E_hat;
  Eigen::Matrix3d S0;  ///< ∂Ψ₀/∂E
  double psi0 = 0.0;
};

void require_finite(const Eigen::Matrix3d& F) {
  if (!F.allFinite()) {
    throw_error("orthotropic Fung: non-finite deformation gradient [{} {} {}; {} {} {}; {} {} {}]", F(0, 0), F(0, 1),
                F(0, 2), F(1, 0), F(1, 1), F(1, 2), F(2, 0), F(2, 1), F(2, 2));
  }
}

/// Ê and Ψ₀ without S₀ (the energy alone); strain_of adds S₀ to the same numbers.
void strain_energy_of(const Eigen::Matrix3d& F, const OrthotropicFung& m, Strain& s) {
  require_finite(F);
  const Eigen::Matrix3d E = green_strain(F);
  s.E_hat = m.scaling * E * m.scaling;  // Ê = P_Y E P_Y (docs/physics.md §1.2)
  const double tr = s.E_hat.trace();
  s.psi0 = m.mu0 * s.E_hat.squaredNorm() + 0.5 * m.lambda0 * tr * tr;  // tr(Ê²) = ‖Ê‖²_F (Ê symmetric)
  require(std::isfinite(s.psi0), "orthotropic Fung: the StVK energy overflows (‖F‖ = {:.4g})", F.norm());
}

Strain strain_of(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  Strain s;
  strain_energy_of(F, m, s);
  const double tr = s.E_hat.trace();
  s.S0 = m.scaling * (2.0 * m.mu0 * s.E_hat + m.lambda0 * tr * Eigen::Matrix3d::Identity()) * m.scaling;
  return s;
}

/// φ(x) = (eˣ − 1) and its first two derivatives, with the overflow policy applied.
struct Fung {
  double phi = 0.0;
  double dphi = 1.0;
  double d2phi = 0.0;
};

Fung fung_factor(double x, const OrthotropicFung& m) {
  Fung f;
  if (m.inv_c == 0.0) return f;  // Fung factor off: Ψ = Ψ₀, handled by the caller
  if (x <= kFungExponentCap) {   // false for NaN, which then reaches the checks below
    f.phi = std::expm1(x);
    f.dphi = std::exp(x);
    f.d2phi = f.dphi;
    return f;
  }
  if (m.overflow == ExponentOverflow::kThrow || !std::isfinite(x)) {
    throw_error(
        "orthotropic Fung: exponent 2Ψ₀/c = {:.4g} exceeds the cap {} (c = {:.4g} Pa); the strain is far "
        "outside the material's range",
        x, kFungExponentCap, m.c);
  }
  const double e_cap = std::exp(kFungExponentCap);
  f.phi = e_cap * (1.0 + (x - kFungExponentCap)) - 1.0;
  f.dphi = e_cap;
  f.d2phi = 0.0;
  return f;
}

double psi_from(const Strain& s, const Fung& f, const OrthotropicFung& m) {
  return m.inv_c == 0.0 ? s.psi0 : 0.5 * m.c * f.phi;  // Ψ = (c/2)(exp(2Ψ₀/c) − 1) (docs/physics.md §1.2)
}

/// ∂²Ψ₀/∂F² column by column: column k is dP₀ for dF = e_i e_jᵀ, k = i + 3j. With G = P_Y² and f_i = Fᵀe_i (row i
/// of F), dE = ½(f_i e_jᵀ + e_j f_iᵀ), so dS₀ = 2μ₀ G dE G + λ₀ tr(G dE) G (P_Y symmetric, trace cyclic) and
///   F dS₀ = μ₀ (F a_i g_jᵀ + F g_j a_iᵀ) + λ₀ a_i(j) F G,   a_i = G f_i,  g_j = G e_j,
/// two outer products per column instead of five 3×3 products (docs/physics.md §1.2).
Matrix9d stvk_hessian(const Eigen::Matrix3d& F, const Strain& s, const OrthotropicFung& m) {
  const Eigen::Matrix3d G = m.scaling * m.scaling;
  const Eigen::Matrix3d FG = F * G;             // column j: F g_j
  const Eigen::Matrix3d A = G * F.transpose();  // column i: a_i = G f_i
  const Eigen::Matrix3d FA = F * A;             // column i: F a_i
  Matrix9d H;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      Eigen::Matrix3d dP = m.mu0 * (FA.col(i) * G.col(j).transpose() + FG.col(j) * A.col(i).transpose()) +
                           (m.lambda0 * A(j, i)) * FG;  // F dS₀; A(j, i) = a_i(j) = tr(G dE)
      dP.row(i) += s.S0.row(j);                         // + dF S₀ = e_i (row j of S₀)
      H.col(i + 3 * j) = Eigen::Map<const Vector9d>(dP.data());
    }
  }
  return H;
}

}  // namespace

OrthotropicFung make_orthotropic_fung(const SkinMaterial& material, const Eigen::Vector3d& normal) {
  validate(material);
  require(normal.allFinite() && std::abs(normal.norm() - 1.0) < 1e-6,
          "orthotropic Fung: the normal must be a unit vector, got ({}, {}, {}) of length {}", normal.x(), normal.y(),
          normal.z(), normal.norm());
  OrthotropicFung m;
  m.normal = normal.normalized();
  const Eigen::Matrix3d nn = m.normal * m.normal.transpose();
  // P_Y = Y_t^{1/4}(I − nnᵀ) + Y_n^{1/4} nnᵀ (docs/physics.md §1.2)
  m.scaling = std::pow(material.young_tangent, 0.25) * (Eigen::Matrix3d::Identity() - nn) +
              std::pow(material.young_normal, 0.25) * nn;
  m.mu0 = unit_lame_mu(material.poisson);
  m.lambda0 = unit_lame_lambda(material.poisson);
  m.c = fung_scale_c(material);
  m.inv_c = std::isinf(m.c) ? 0.0 : 1.0 / m.c;
  m.overflow = material.overflow;
  return m;
}

Eigen::Matrix3d green_strain(const Eigen::Matrix3d& F) {
  return 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
}

double psi_ortho_stvk(const Eigen::Matrix3d& F, const OrthotropicFung& m) { return strain_of(F, m).psi0; }

Eigen::Matrix3d dpsi_ortho_stvk_dF(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  return F * strain_of(F, m).S0;
}

Matrix9d d2psi_ortho_stvk_dF2(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  return stvk_hessian(F, strain_of(F, m), m);
}

double fung_exponent(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  return 2.0 * strain_of(F, m).psi0 * m.inv_c;
}

FungStrain fung_strain(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  const Strain s = strain_of(F, m);
  return {2.0 * s.psi0 * m.inv_c, s.E_hat.norm()};
}

// The three share strain_energy_of, fung_factor and psi_from (through eval_ortho_fung for the derivatives) so that they
// return bit-identical numbers to one combined evaluation; the energy alone skips S₀ and P (output fields, line
// searches).
double psi_ortho_fung(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  Strain s;
  strain_energy_of(F, m, s);
  return psi_from(s, fung_factor(2.0 * s.psi0 * m.inv_c, m), m);
}

Eigen::Matrix3d dpsi_ortho_fung_dF(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  return eval_ortho_fung(F, m, false).P;
}

Matrix9d d2psi_ortho_fung_dF2(const Eigen::Matrix3d& F, const OrthotropicFung& m) {
  return eval_ortho_fung(F, m, true).dPdF;
}

OrthoFungValues eval_ortho_fung(const Eigen::Matrix3d& F, const OrthotropicFung& m, bool with_hessian) {
  const Strain s = strain_of(F, m);
  const Fung f = fung_factor(2.0 * s.psi0 * m.inv_c, m);
  OrthoFungValues v;
  v.psi = psi_from(s, f, m);
  const Eigen::Matrix3d P0 = F * s.S0;
  v.P = f.dphi * P0;
  if (with_hessian) {
    // dP = g[dF S₀ + F ℂ₀:dE] + (2g/c)(P₀:dF) P₀ (docs/physics.md §1.2, dS = g[ℂ₀:dE + (2/c)(S₀:dE)S₀])
    v.dPdF = f.dphi * stvk_hessian(F, s, m);
    if (m.inv_c != 0.0) {
      const Eigen::Map<const Vector9d> p0(P0.data());
      v.dPdF.noalias() += (2.0 * m.inv_c * f.d2phi) * p0 * p0.transpose();
    }
  }
  return v;
}

Eigen::Matrix3d cauchy_stress(const Eigen::Matrix3d& F, const Eigen::Matrix3d& P) {
  const double J = F.determinant();
  require(J > 0.0, "Cauchy stress: det F = {} is not positive (inverted element)", J);
  return P * F.transpose() / J;  // σ = J⁻¹ P Fᵀ
}

}  // namespace sflsh::material
