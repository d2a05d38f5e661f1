#pragma once
// Material curves: homogeneous stress–strain responses of the orthotropic StVK–Fung material, solved
// exactly (no mesh), with the normal n = z. For checking the model by eye and against other FEM codes
// (docs/material.md):
//  - uniaxial_tangent: stretch λ = 1 + ε along x (in the tangent plane); the lateral stretches along y and
//    z are solved by Newton so that the lateral faces are traction-free (σ_yy = σ_zz = 0); stress = σ_xx.
//  - uniaxial_normal: the same along z (= n); lateral x and y traction-free; stress = σ_zz.
//  - shear: simple shear of the tangent plane against the normal, x += γ z (F = I + γ e_x e_zᵀ), strain = γ;
//    stress = σ_xz. Simple shear is a prescribed deformation: the normal stresses it causes stay.
// Stresses are Cauchy stresses in Pa; strains are engineering strains (stretch − 1) or the shear γ.
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::material {

enum class CurveTest { kUniaxialTangent, kUniaxialNormal, kShear };

/// All tests, in the order of curves.csv.
inline constexpr CurveTest kCurveTests[] = {CurveTest::kUniaxialTangent, CurveTest::kUniaxialNormal, CurveTest::kShear};

/// "uniaxial_tangent", "uniaxial_normal", "shear" (the `test` column of curves.csv).
std::string_view curve_test_name(CurveTest test);

/// The strain range of a test: [−0.3, 0.5] for the uniaxial tests, [0, 0.5] for shear.
struct StrainRange {
  double lo = 0.0;
  double hi = 0.0;
};
StrainRange curve_strain_range(CurveTest test);

/// One solved homogeneous state.
struct CurvePoint {
  double strain = 0.0;                              ///< ε = stretch − 1, or γ for shear
  double stress = 0.0;                              ///< the Cauchy stress component of the test [Pa]
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();  ///< the deformation gradient (lateral stretches solved)
};

/// The state of `test` at `strain`. Uniaxial tests solve the two lateral stretches by Newton (with
/// backtracking) on the lateral first Piola–Kirchhoff stresses (≡ minimizing Ψ over them) until
/// |P_lat| ≤ 1e-11·max(Y_t, Y_n, max|P|), i.e. rounding level,
/// starting from `lateral_guess` (or the small-strain guess 1 − ν_lat ε when it is null).
/// Throws sflsh::Error for an invalid material, a stretch ≤ 0, or no convergence in 100 iterations.
CurvePoint curve_point(const SkinMaterial& material, CurveTest test, double strain,
                       const Eigen::Vector2d* lateral_guess = nullptr);

struct MaterialCurve {
  CurveTest test = CurveTest::kUniaxialTangent;
  std::vector<CurvePoint> points;  ///< by increasing strain
};

/// One curve sampled at strains k·step over curve_strain_range(test) (ε = 0 is a sample).
MaterialCurve material_curve(const SkinMaterial& material, CurveTest test, double strain_step = 0.01);
/// The three curves, in kCurveTests order.
std::vector<MaterialCurve> material_curves(const SkinMaterial& material, double strain_step = 0.01);

/// Writes `test,strain,stress` rows (header exactly that; shortest round-trip decimals) atomically.
void write_curves_csv(const std::filesystem::path& path, const std::vector<MaterialCurve>& curves);

/// Plots stress [kPa] against strain, one line per curve, into a PNG (atomic write) with VTK's charts,
/// offscreen. Throws sflsh::Error when no X display is available (Debian's VTK renders through X; run
/// under `xvfb-run -a`).
void plot_curves_png(const std::filesystem::path& path, const std::vector<MaterialCurve>& curves,
                     const std::string& title);

}  // namespace sflsh::material
