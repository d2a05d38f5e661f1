// The orthotropic StVK–Fung energy density: derivatives by finite differences over deformation regimes,
// agreement with an independently written energy, invariances, the small-strain constants, the Fung
// stiffening law, FEBio's parameterization, and the overflow guard.
#include "error_of.hpp"
#include "finite_difference.hpp"
#include "reference_energy.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/material/orthotropic_fung.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>

namespace sflsh {

using namespace sflsh::material;
using sflsh::testing::central_gradient;
using sflsh::testing::central_jacobian;
using sflsh::testing::random_rotation;
using sflsh::testing::relative_error;
using ::testing::HasSubstr;

namespace {

enum class Regime { kStretch, kCompression, kShear, kNearInversion, kInverted };

std::string regime_name(Regime r) {
  switch (r) {
    case Regime::kStretch:
      return "stretch";
    case Regime::kCompression:
      return "compression";
    case Regime::kShear:
      return "shear";
    case Regime::kNearInversion:
      return "near_inversion";
    case Regime::kInverted:
      return "inverted";
  }
  return "?";
}

/// A random F of the regime: U Σ Vᵀ with the regime's singular values, or a rotated simple shear.
Eigen::Matrix3d random_F(Regime regime, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Matrix3d U = random_rotation(rng), V = random_rotation(rng);
  Eigen::Vector3d s;
  switch (regime) {
    case Regime::kStretch:
      s << 1.05 + 0.3 * u(rng), 1.0 + 0.2 * u(rng), 0.95 + 0.2 * u(rng);
      break;
    case Regime::kCompression:
      s << 0.6 + 0.35 * u(rng), 0.7 + 0.25 * u(rng), 0.8 + 0.2 * u(rng);
      break;
    case Regime::kNearInversion:
      s << 0.9 + 0.2 * u(rng), 0.9 + 0.2 * u(rng), 0.05 + 0.1 * u(rng);
      break;
    case Regime::kInverted:
      s << 0.9 + 0.2 * u(rng), 0.9 + 0.2 * u(rng), -(0.1 + 0.2 * u(rng));
      break;
    case Regime::kShear: {
      Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
      F(0, 1) = 0.8 * u(rng) - 0.4;
      F(1, 2) = 0.8 * u(rng) - 0.4;
      F(2, 0) = 0.8 * u(rng) - 0.4;
      return U * F;
    }
  }
  return U * s.asDiagonal() * V.transpose();
}

SkinMaterial skin(double yt, double yn, double nu = 0.2, double s = 4.0) {
  SkinMaterial m;
  m.young_tangent = yt;
  m.young_normal = yn;
  m.poisson = nu;
  m.saturation = s;
  return m;
}

// Materials: SFLSH's defaults with a softer normal, a stiff normal with auxetic ν and strong saturation,
// the other reading of c, and the Fung factor off (plain orthotropic StVK).
SkinMaterial constitutive_case(int k) {
  if (k == 0) return skin(5000.0, 2000.0);
  if (k == 1) return skin(1000.0, 20000.0, -0.3, 8.0);
  SkinMaterial m = skin(3000.0, 3000.0 * 0.4, 0.45, 4.0);
  m.fung_scale = k == 2 ? FungScale::kTangentTimesSaturation : FungScale::kNone;
  return m;
}

Eigen::Vector3d normal_case(int k) {
  if (k == 0) return Eigen::Vector3d::UnitZ();
  return Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
}

Vector9d vec(const Eigen::Matrix3d& F) { return Eigen::Map<const Vector9d>(F.data()); }
Eigen::Matrix3d unvec(const Vector9d& v) { return Eigen::Map<const Eigen::Matrix3d>(v.data()); }

class Derivatives : public ::testing::TestWithParam<std::tuple<Regime, int, int>> {};

}  // namespace

// Each regime × material × normal: 4 random F. h = 1e-6 on F entries of order one: the central-difference
// truncation (h²·|Ψ'''|/|Ψ'| ≲ 1e-12·(∂x/∂F)² with the Fung exponent x ≲ 20 here) and rounding
// (ε·|Ψ|/h ≈ 1e-10 relative) both stay below 1e-8, so 1e-6 relative to the largest entry is a safe bound
// that still catches any wrong term (those are O(1) relative).
TEST_P(Derivatives, GradientAndHessianMatchFiniteDifferences) {
  const auto [regime, mat, nrm] = GetParam();
  const OrthotropicFung m = make_orthotropic_fung(constitutive_case(mat), normal_case(nrm));
  std::mt19937 rng(1000 + 100 * static_cast<int>(regime) + 10 * mat + nrm);
  for (int sample = 0; sample < 4; ++sample) {
    const Eigen::Matrix3d F = random_F(regime, rng);
    SCOPED_TRACE(regime_name(regime) + " sample " + std::to_string(sample));
    const auto psi = [&](const Vector9d& f) { return psi_ortho_fung(unvec(f), m); };
    const auto piola = [&](const Vector9d& f) -> Vector9d { return vec(dpsi_ortho_fung_dF(unvec(f), m)); };
    const Vector9d P = piola(vec(F));
    const Matrix9d H = d2psi_ortho_fung_dF2(F, m);
    EXPECT_LT(relative_error(central_gradient<9>(psi, vec(F), 1e-6), P), 1e-6);
    EXPECT_LT(relative_error(central_jacobian<9, 9>(piola, vec(F), 1e-6), H), 1e-6);
    // Symmetric as a second derivative must be; the two terms are symmetric in exact arithmetic, so the
    // asymmetry is rounding, ~1e-16 relative (1e-13 allows for the sums).
    EXPECT_LT(sflsh::testing::asymmetry(H), 1e-13);
    // The combined evaluation is the same computation as the separate functions.
    const OrthoFungValues all = eval_ortho_fung(F, m, true);
    EXPECT_DOUBLE_EQ(all.psi, psi_ortho_fung(F, m));
    EXPECT_EQ(all.P, dpsi_ortho_fung_dF(F, m));
    EXPECT_EQ(all.dPdF, H);
  }
}

// The independent energy (Voigt stiffness from engineering constants, complex-step P) must give the same
// Ψ and P. Both are exact formulas evaluated in double: the differences are rounding, amplified at most
// by the compliance inversion (condition ≲ 1e2 here), so 1e-11 relative.
TEST_P(Derivatives, AgreesWithIndependentlyWrittenEnergy) {
  const auto [regime, mat, nrm] = GetParam();
  const SkinMaterial sm = constitutive_case(mat);
  const OrthotropicFung m = make_orthotropic_fung(sm, normal_case(nrm));
  const auto ref = sflsh::testing::reference_material(sm, normal_case(nrm));
  std::mt19937 rng(2000 + 100 * static_cast<int>(regime) + 10 * mat + nrm);
  for (int sample = 0; sample < 4; ++sample) {
    const Eigen::Matrix3d F = random_F(regime, rng);
    const double psi = psi_ortho_fung(F, m);
    EXPECT_NEAR(psi, sflsh::testing::reference_psi<double>(F, ref), 1e-11 * std::abs(psi));
    EXPECT_LT(relative_error(dpsi_ortho_fung_dF(F, m), sflsh::testing::reference_piola(F, ref)), 1e-11);
  }
}

INSTANTIATE_TEST_SUITE_P(Regimes, Derivatives,
                         ::testing::Combine(::testing::Values(Regime::kStretch, Regime::kCompression, Regime::kShear,
                                                              Regime::kNearInversion, Regime::kInverted),
                                            ::testing::Values(0, 1, 2, 3), ::testing::Values(0, 1)),
                         [](const auto& p) {
                           return regime_name(std::get<0>(p.param)) + "_material" +
                                  std::to_string(std::get<1>(p.param)) + "_normal" +
                                  std::to_string(std::get<2>(p.param));
                         });

// Ψ₀ and its derivatives are the Fung-off energy, bit for bit apart from the factor 1 (g = 1).
TEST(OrthotropicFung, StvkPartIsTheEnergyWithTheFungFactorOff) {
  const OrthotropicFung with = make_orthotropic_fung(constitutive_case(2), normal_case(1));
  SkinMaterial off_material = constitutive_case(2);
  off_material.fung_scale = FungScale::kNone;
  const OrthotropicFung off = make_orthotropic_fung(off_material, normal_case(1));
  std::mt19937 rng(9);
  for (int k = 0; k < 5; ++k) {
    const Eigen::Matrix3d F = random_F(Regime::kStretch, rng);
    EXPECT_EQ(psi_ortho_stvk(F, with), psi_ortho_fung(F, off));
    EXPECT_EQ(dpsi_ortho_stvk_dF(F, with), dpsi_ortho_fung_dF(F, off));
    EXPECT_EQ(d2psi_ortho_stvk_dF2(F, with), d2psi_ortho_fung_dF2(F, off));
    EXPECT_GT(psi_ortho_fung(F, with), psi_ortho_stvk(F, with));  // the Fung factor only adds: eˣ − 1 > x
  }
}

TEST(OrthotropicFung, ZeroEnergyAndStressAtRestAndUnderRotation) {
  const OrthotropicFung m = make_orthotropic_fung(constitutive_case(0), normal_case(1));
  EXPECT_EQ(psi_ortho_fung(Eigen::Matrix3d::Identity(), m), 0.0);
  EXPECT_EQ(dpsi_ortho_fung_dF(Eigen::Matrix3d::Identity(), m), Eigen::Matrix3d::Zero());
  std::mt19937 rng(7);
  for (int k = 0; k < 5; ++k) {
    const Eigen::Matrix3d R = random_rotation(rng);
    // RᵀR = I to ~1e-16, so E ~ 1e-16, Ψ ~ Y·1e-32 and P ~ Y·1e-16: bounds 1e-20·Y and 1e-13·Y.
    EXPECT_LT(std::abs(psi_ortho_fung(R, m)), 1e-20 * 5000.0);
    EXPECT_LT(dpsi_ortho_fung_dF(R, m).cwiseAbs().maxCoeff(), 1e-13 * 5000.0);
  }
}

// Objectivity Ψ(QF) = Ψ(F), P(QF) = Q P(F); transverse isotropy Ψ(F Q_n) = Ψ(F) for Q_n about n; and
// frame covariance Ψ(Q F Qᵀ; Q n) = Ψ(F; n). Rounding only: 1e-12 relative.
TEST(OrthotropicFung, RotationInvariance) {
  const Eigen::Vector3d n = normal_case(1);
  const SkinMaterial sm = constitutive_case(0);
  const OrthotropicFung m = make_orthotropic_fung(sm, n);
  std::mt19937 rng(11);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Matrix3d F = random_F(k % 2 ? Regime::kStretch : Regime::kShear, rng);
    const Eigen::Matrix3d Q = random_rotation(rng);
    const double psi = psi_ortho_fung(F, m);
    EXPECT_NEAR(psi_ortho_fung(Q * F, m), psi, 1e-12 * psi);
    EXPECT_LT(relative_error(dpsi_ortho_fung_dF(Q * F, m), Q * dpsi_ortho_fung_dF(F, m)), 1e-12);
    const Eigen::Matrix3d Qn = Eigen::AngleAxisd(0.3 + k, n).toRotationMatrix();
    EXPECT_NEAR(psi_ortho_fung(F * Qn, m), psi, 1e-12 * psi);
    const OrthotropicFung rotated = make_orthotropic_fung(sm, Q * n);
    EXPECT_NEAR(psi_ortho_fung(Q * F * Q.transpose(), rotated), psi, 1e-12 * psi);
    // Not invariant under a rotation that tilts n: the material is anisotropic (Y_t ≠ Y_n).
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.7, n.unitOrthogonal()).toRotationMatrix();
    EXPECT_GT(std::abs(psi_ortho_fung(F * tilt, m) - psi), 1e-3 * psi);
  }
}

// At F = I, dP/dF is the linear stiffness ℂ (dP = ℂ:sym dF). Invert its normal block into the compliance
// and read E_i = 1/S_ii, ν_ij = −S_ij E_i; G_ij = ∂P_ij/∂F_ij. They must be the constants of docs/physics.md
// §1.2 and of small_strain_constants(). The 3×3 inverse is well conditioned (≲ 30): 1e-12 relative.
TEST(OrthotropicFung, SmallStrainLimitIsTheLinearOrthotropicMaterial) {
  for (int axis : {2, 0}) {  // n = z, and n = x (checks that the frame follows n)
    const SkinMaterial sm = skin(5000.0, 2000.0, 0.2, 4.0);
    const OrthotropicFung m = make_orthotropic_fung(sm, Eigen::Vector3d::Unit(axis));
    const Matrix9d H = d2psi_ortho_fung_dF2(Eigen::Matrix3d::Identity(), m);
    // Axes in the material frame (t₁, t₂, n).
    const int ax[3] = {(axis + 1) % 3, (axis + 2) % 3, axis};
    Eigen::Matrix3d C;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) C(a, b) = H(4 * ax[a], 4 * ax[b]);
    const Eigen::Matrix3d S = C.inverse();
    const double nu = 0.2, yt = 5000.0, yn = 2000.0;
    const OrthotropicConstants k = small_strain_constants(sm);
    const double tol = 1e-12;
    EXPECT_NEAR(1.0 / S(0, 0), yt, tol * yt);
    EXPECT_NEAR(1.0 / S(1, 1), yt, tol * yt);
    EXPECT_NEAR(1.0 / S(2, 2), yn, tol * yn);
    EXPECT_NEAR(-S(0, 1) / S(0, 0), nu, tol);                       // ν₁₂ = ν
    EXPECT_NEAR(-S(1, 2) / S(1, 1), nu * std::sqrt(yt / yn), tol);  // ν₂₃ = ν √(E₂/E₃)
    EXPECT_NEAR(-S(2, 0) / S(2, 2), nu * std::sqrt(yn / yt), tol);  // ν₃₁ = ν √(E₃/E₁)
    auto shear = [&](int a, int b) { return H(ax[a] + 3 * ax[b], ax[a] + 3 * ax[b]); };
    EXPECT_NEAR(shear(0, 1), yt / (2.0 * (1.0 + nu)), tol * yt);
    EXPECT_NEAR(shear(1, 2), std::sqrt(yt * yn) / (2.0 * (1.0 + nu)), tol * yt);
    EXPECT_NEAR(shear(2, 0), std::sqrt(yt * yn) / (2.0 * (1.0 + nu)), tol * yt);
    EXPECT_NEAR(k.E1, 1.0 / S(0, 0), tol * yt);
    EXPECT_NEAR(k.E3, 1.0 / S(2, 2), tol * yt);
    EXPECT_NEAR(k.nu12, -S(0, 1) / S(0, 0), tol);
    EXPECT_NEAR(k.nu23, -S(1, 2) / S(1, 1), tol);
    EXPECT_NEAR(k.nu31, -S(2, 0) / S(2, 2), tol);
    EXPECT_NEAR(k.G12, shear(0, 1), tol * yt);
    EXPECT_NEAR(k.G23, shear(1, 2), tol * yt);
    EXPECT_NEAR(k.G31, shear(2, 0), tol * yt);
    EXPECT_DOUBLE_EQ(k.c, yt / 4.0);
  }
}

// Laterally constrained stretch F = diag(λ, 1, 1) along a tangent axis: Ψ₀ = ½ C₁₁ E², C₁₁ = (λ₀+2μ₀) Y_t,
// so Ψ = (c/2)(e^{kE²} − 1) with k = C₁₁/c: S = C₁₁ E e^{kE²} and dS/dE = C₁₁ e^{kE²}(1 + 2kE²). Read
// dS/dE from dP/dF: d²Ψ/dλ² = Ψ''(E) λ² + Ψ'(E). Closed form vs double evaluation: 1e-12 relative.
TEST(OrthotropicFung, FungFactorStiffensAsTheClosedForm) {
  for (const FungScale scale :
       {FungScale::kTangentOverSaturation, FungScale::kTangentTimesSaturation, FungScale::kNone}) {
    SkinMaterial sm = skin(5000.0, 2000.0);
    sm.fung_scale = scale;
    const OrthotropicFung m = make_orthotropic_fung(sm, Eigen::Vector3d::UnitZ());
    const double c11 = (m.lambda0 + 2.0 * m.mu0) * sm.young_tangent;
    const double k = c11 * m.inv_c;
    auto tangent = [&](double stretch) {
      const Eigen::Matrix3d F = Eigen::Vector3d(stretch, 1.0, 1.0).asDiagonal();
      const OrthoFungValues v = eval_ortho_fung(F, m, true);
      return (v.dPdF(0, 0) - v.P(0, 0) / stretch) / (stretch * stretch);
    };
    EXPECT_NEAR(tangent(1.0), c11, 1e-12 * c11);
    for (double stretch : {0.8, 1.1, 1.3, 1.5}) {
      const double E = 0.5 * (stretch * stretch - 1.0);
      const double predicted = std::exp(k * E * E) * (1.0 + 2.0 * k * E * E);
      EXPECT_NEAR(tangent(stretch) / tangent(1.0), predicted, 1e-12 * predicted) << stretch;
      const Eigen::Matrix3d F = Eigen::Vector3d(stretch, 1.0, 1.0).asDiagonal();
      const double S11 = dpsi_ortho_fung_dF(F, m)(0, 0) / stretch;
      EXPECT_NEAR(S11, c11 * E * std::exp(k * E * E), 1e-12 * std::abs(S11));
    }
  }
  // docs/physics.md §1.2's reading of saturation 4 (ν ignored, c = Y_t/4): the secant stiffness S/E grows by
  // exactly e at a tangential Green strain of 0.5.
  const OrthotropicFung m = make_orthotropic_fung(skin(5000.0, 2000.0, 0.0, 4.0), Eigen::Vector3d::UnitZ());
  const double stretch = std::sqrt(2.0);  // E = ½(λ² − 1) = 0.5
  const double secant = dpsi_ortho_fung_dF(Eigen::Vector3d(stretch, 1.0, 1.0).asDiagonal(), m)(0, 0) / stretch / 0.5;
  EXPECT_NEAR(secant / 5000.0, std::exp(1.0), 1e-12);
}

// FEBio's "Fung-ortho-compressible" with the documented parameters and K = 0: μ_a, λ_ab as FEBio's
// Validate() builds them from E_i, G_ij, ν_ij, and cQ = Σ_a [2μ_a A_a:E² + Σ_b λ_ab (A_a:E)(A_b:E)],
// W = ½c(e^Q − 1). It must equal our Ψ at finite strain (1e-11: rounding through a 3×3 inverse).
TEST(OrthotropicFung, FebioParametersReproduceTheEnergy) {
  const SkinMaterial sm = skin(5000.0, 2000.0);
  const Eigen::Vector3d n = normal_case(1);
  const OrthotropicFung m = make_orthotropic_fung(sm, n);
  const OrthotropicConstants k = small_strain_constants(sm);
  const double mu[3] = {k.G12 + k.G31 - k.G23, k.G12 - k.G31 + k.G23, -k.G12 + k.G31 + k.G23};
  Eigen::Matrix3d compliance;
  compliance << 1.0 / k.E1, -k.nu12 / k.E1, -k.nu31 / k.E3, -k.nu12 / k.E1, 1.0 / k.E2, -k.nu23 / k.E2, -k.nu31 / k.E3,
      -k.nu23 / k.E2, 1.0 / k.E3;
  Eigen::Matrix3d lam = compliance.inverse();
  for (int a = 0; a < 3; ++a) lam(a, a) -= 2.0 * mu[a];
  const Eigen::Vector3d a3 = n, a1 = n.unitOrthogonal(), a2 = a3.cross(a1);
  const Eigen::Vector3d axes[3] = {a1, a2, a3};
  std::mt19937 rng(5);
  for (int s = 0; s < 6; ++s) {
    const Eigen::Matrix3d F = random_F(s % 2 ? Regime::kShear : Regime::kStretch, rng);
    const Eigen::Matrix3d E = green_strain(F);
    double cQ = 0.0;
    for (int a = 0; a < 3; ++a) {
      cQ += 2.0 * mu[a] * axes[a].dot(E * E * axes[a]);
      for (int b = 0; b < 3; ++b) cQ += lam(a, b) * axes[a].dot(E * axes[a]) * axes[b].dot(E * axes[b]);
    }
    const double W = 0.5 * k.c * (std::exp(cQ / k.c) - 1.0);
    EXPECT_NEAR(W, psi_ortho_fung(F, m), 1e-11 * W);
  }
}

TEST(OrthotropicFung, ExponentAboveTheCapThrowsOrContinuesLinearly) {
  SkinMaterial sm = skin(5000.0, 2000.0);
  const OrthotropicFung m = make_orthotropic_fung(sm, Eigen::Vector3d::UnitZ());
  const Eigen::Matrix3d huge = Eigen::Vector3d(4.0, 1.0, 1.0).asDiagonal();  // E₁₁ = 7.5: x ≈ 250
  ASSERT_GT(fung_exponent(huge, m), kFungExponentCap);
  EXPECT_THAT(sflsh::testing::error_of([&] { psi_ortho_fung(huge, m); }), HasSubstr("exceeds the cap"));
  EXPECT_THROW(dpsi_ortho_fung_dF(huge, m), Error);
  EXPECT_THROW(d2psi_ortho_fung_dF2(huge, m), Error);

  sm.overflow = ExponentOverflow::kContinueLinearly;
  const OrthotropicFung lin = make_orthotropic_fung(sm, Eigen::Vector3d::UnitZ());
  const OrthoFungValues v = eval_ortho_fung(huge, lin, true);
  EXPECT_TRUE(std::isfinite(v.psi) && v.P.allFinite() && v.dPdF.allFinite());
  EXPECT_GT(v.psi, psi_ortho_fung(Eigen::Vector3d(3.3, 1.0, 1.0).asDiagonal(), lin));  // still growing
  // Beyond the cap the energy is e^{cap}·(linear in Ψ₀): the derivatives stay consistent. Relative h:
  // the entries are ~1e45, so the bound is relative too (1e-6, as in the regime tests).
  const auto psi = [&](const Vector9d& f) { return psi_ortho_fung(unvec(f), lin); };
  EXPECT_LT(relative_error(central_gradient<9>(psi, vec(huge), 1e-6), vec(v.P)), 1e-6);

  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 2) = std::nan("");
  EXPECT_THAT(sflsh::testing::error_of([&] { psi_ortho_fung(nan, lin); }), HasSubstr("non-finite"));
  // Below the cap nothing changes: the exponent is 2Ψ₀/c.
  const Eigen::Matrix3d F = Eigen::Vector3d(1.3, 0.9, 1.1).asDiagonal();
  const double x = 2.0 * psi_ortho_stvk(F, m) / (5000.0 / 4.0);
  EXPECT_NEAR(fung_exponent(F, m), x, 1e-14 * x);  // a few ulps apart (1/c rounded once)
  EXPECT_EQ(psi_ortho_fung(F, lin), psi_ortho_fung(F, m));
}

TEST(SkinMaterial, ValidationNamesTheBadField) {
  using sflsh::testing::error_of;
  EXPECT_THAT(error_of([] { validate(skin(-1.0, 2000.0)); }), HasSubstr("young_tangent"));
  EXPECT_THAT(error_of([] { validate(skin(5000.0, 0.0)); }), HasSubstr("young_normal"));
  EXPECT_THAT(error_of([] { validate(skin(std::nan(""), 2000.0)); }), HasSubstr("young_tangent"));
  EXPECT_THAT(error_of([] { validate(skin(5000.0, 2000.0, 0.5)); }), HasSubstr("poisson"));
  EXPECT_THAT(error_of([] { validate(skin(5000.0, 2000.0, -1.0)); }), HasSubstr("poisson"));
  EXPECT_THAT(error_of([] { validate(skin(5000.0, 2000.0, 0.2, 0.0)); }), HasSubstr("saturation"));
  EXPECT_THAT(error_of([] {
                validate(skin(5000.0, 2000.0, 0.2, -4.0), {"a", "b", "c", "--saturation"});
              }),
              HasSubstr("--saturation"));
  EXPECT_NO_THROW(validate(skin(5000.0, 2000.0, -0.99, 1e-3)));
  EXPECT_THAT(error_of([] { make_orthotropic_fung(skin(5000.0, 2000.0), Eigen::Vector3d(0, 0, 2)); }),
              HasSubstr("unit vector"));
  EXPECT_THAT(error_of([] { make_orthotropic_fung(skin(5000.0, 0.0), Eigen::Vector3d::UnitZ()); }),
              HasSubstr("young_normal"));
}

}  // namespace sflsh
