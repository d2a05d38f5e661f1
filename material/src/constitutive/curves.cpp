#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/material/curves.hpp>
#include <sflsh/material/orthotropic_fung.hpp>

#include <Eigen/LU>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace sflsh::material {

namespace {

constexpr int kMaxNewtonIterations = 100;

/// The loading axis and the two traction-free lateral axes of a uniaxial test (n = z).
struct UniaxialAxes {
  int load = 0;
  int lateral[2] = {1, 2};
};

UniaxialAxes axes_of(CurveTest test) {
  if (test == CurveTest::kUniaxialNormal) return {2, {0, 1}};
  return {0, {1, 2}};
}

double young_along(const SkinMaterial& material, int axis) {
  return axis == 2 ? material.young_normal : material.young_tangent;
}

Eigen::Matrix3d stretch_matrix(const UniaxialAxes& axes, double stretch, const Eigen::Vector2d& lateral) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  F(axes.load, axes.load) = stretch;
  F(axes.lateral[0], axes.lateral[0]) = lateral(0);
  F(axes.lateral[1], axes.lateral[1]) = lateral(1);
  return F;
}

/// Diagonal F: P is diagonal too (Ê, S₀ diagonal in the frame of n = z), so the lateral faces are
/// traction-free exactly when the two lateral diagonal entries of P vanish. P_ll = ∂Ψ/∂λ_l, so this is
/// Newton minimization of Ψ over the lateral stretches; the 2×2 Jacobian is a block of dP/dF.
CurvePoint uniaxial_point(const SkinMaterial& material, const OrthotropicFung& m, const UniaxialAxes& axes,
                          double strain, const Eigen::Vector2d* guess) {
  const double stretch = 1.0 + strain;
  require(stretch > 0.0, "material curve: strain {} gives a non-positive stretch", strain);
  Eigen::Vector2d lateral;
  if (guess) {
    lateral = *guess;
  } else {  // small-strain guess: ε_lat = −ν_{load,lat} ε with ν_ij = ν √(E_i/E_j)
    for (int k = 0; k < 2; ++k)
      lateral(k) = 1.0 - material.poisson *
                             std::sqrt(young_along(material, axes.load) / young_along(material, axes.lateral[k])) *
                             strain;
  }
  const int k0 = axes.lateral[0] * 4;  // vec index of F(l, l) is l + 3l
  const int k1 = axes.lateral[1] * 4;
  auto residual = [&](const Eigen::Vector2d& l, OrthoFungValues& v) {
    v = eval_ortho_fung(stretch_matrix(axes, stretch, l), m, true);
    return Eigen::Vector2d(v.P(axes.lateral[0], axes.lateral[0]), v.P(axes.lateral[1], axes.lateral[1]));
  };
  OrthoFungValues v;
  Eigen::Vector2d r = residual(lateral, v);
  for (int iteration = 0;; ++iteration) {
    // Converged when the lateral stresses are at rounding level of the stresses present.
    const double scale = std::max({material.young_tangent, material.young_normal, v.P.cwiseAbs().maxCoeff()});
    if (r.lpNorm<Eigen::Infinity>() <= 1e-11 * scale) break;
    require(iteration < kMaxNewtonIterations,
            "material curve: lateral stretches did not converge at strain {} (|P_lat| = {:.3g} Pa)", strain,
            r.lpNorm<Eigen::Infinity>());
    Eigen::Matrix2d J;
    J << v.dPdF(k0, k0), v.dPdF(k0, k1), v.dPdF(k1, k0), v.dPdF(k1, k1);
    const Eigen::Vector2d step = -J.fullPivLu().solve(r);
    require(step.allFinite(), "material curve: singular lateral stiffness at strain {}", strain);
    // Backtracking on the residual norm, keeping the stretches positive.
    double t = 1.0;
    Eigen::Vector2d trial_r;
    OrthoFungValues trial_v;
    for (int halvings = 0;; ++halvings) {
      const Eigen::Vector2d trial = lateral + t * step;
      if (trial.minCoeff() > 0.0) {
        trial_r = residual(trial, trial_v);
        if (trial_r.norm() < r.norm() || halvings >= 30) {
          lateral = trial;
          break;
        }
      }
      t *= 0.5;
      require(halvings < 60, "material curve: no admissible lateral step at strain {}", strain);
    }
    r = trial_r;
    v = trial_v;
  }
  CurvePoint point;
  point.strain = strain;
  point.F = stretch_matrix(axes, stretch, lateral);
  point.stress = cauchy_stress(point.F, v.P)(axes.load, axes.load);
  return point;
}

}  // namespace

std::string_view curve_test_name(CurveTest test) {
  switch (test) {
    case CurveTest::kUniaxialTangent:
      return "uniaxial_tangent";
    case CurveTest::kUniaxialNormal:
      return "uniaxial_normal";
    case CurveTest::kShear:
      return "shear";
  }
  throw_error("unknown CurveTest value {}", static_cast<int>(test));
}

StrainRange curve_strain_range(CurveTest test) {
  if (test == CurveTest::kShear) return {0.0, 0.5};
  return {-0.3, 0.5};
}

CurvePoint curve_point(const SkinMaterial& material, CurveTest test, double strain,
                       const Eigen::Vector2d* lateral_guess) {
  const OrthotropicFung m = make_orthotropic_fung(material, Eigen::Vector3d::UnitZ());
  if (test != CurveTest::kShear) return uniaxial_point(material, m, axes_of(test), strain, lateral_guess);
  CurvePoint point;  // simple shear x += γ z: F = I + γ e_x e_zᵀ, J = 1
  point.strain = strain;
  point.F(0, 2) = strain;
  point.stress = cauchy_stress(point.F, dpsi_ortho_fung_dF(point.F, m))(0, 2);
  return point;
}

MaterialCurve material_curve(const SkinMaterial& material, CurveTest test, double strain_step) {
  validate(material);
  const StrainRange range = curve_strain_range(test);
  require(strain_step > 0.0 && strain_step <= range.hi - range.lo,
          "material curve: strain step must lie in (0, {}], got {}", range.hi - range.lo, strain_step);
  // Samples k·step, k = k_lo..k_hi, walked outward from ε = 0 so that each solve starts from its
  // neighbour's lateral stretches (continuation).
  const long k_lo = std::lround(std::ceil(range.lo / strain_step - 1e-9));
  const long k_hi = std::lround(std::floor(range.hi / strain_step + 1e-9));
  MaterialCurve curve;
  curve.test = test;
  curve.points.resize(static_cast<std::size_t>(k_hi - k_lo + 1));
  auto lateral_of = [&](const CurvePoint& p) {
    const UniaxialAxes axes = axes_of(test);
    return Eigen::Vector2d(p.F(axes.lateral[0], axes.lateral[0]), p.F(axes.lateral[1], axes.lateral[1]));
  };
  for (int direction : {+1, -1}) {
    Eigen::Vector2d guess(1.0, 1.0);
    const long k_end = direction > 0 ? k_hi : k_lo;
    for (long k = 0; direction * k <= direction * k_end; k += direction) {
      CurvePoint p = curve_point(material, test, static_cast<double>(k) * strain_step, &guess);
      guess = lateral_of(p);
      curve.points[static_cast<std::size_t>(k - k_lo)] = p;
    }
  }
  return curve;
}

std::vector<MaterialCurve> material_curves(const SkinMaterial& material, double strain_step) {
  std::vector<MaterialCurve> curves;
  for (CurveTest test : kCurveTests) curves.push_back(material_curve(material, test, strain_step));
  return curves;
}

void write_curves_csv(const std::filesystem::path& path, const std::vector<MaterialCurve>& curves) {
  std::string text = "test,strain,stress\n";
  for (const MaterialCurve& curve : curves)
    for (const CurvePoint& p : curve.points)
      text += fmt::format("{},{},{}\n", curve_test_name(curve.test), p.strain, p.stress);
  write_text_atomically(path, text);
}

}  // namespace sflsh::material
