#pragma once
// The hidden material of the synthetic ground truth: κ(s, β) = (h, Y_t, Y_n) at every region vertex of a
// subject. Built in (the default): smooth over the template surface and shape-dependent through the change of
// the local soft-tissue depth with shape, d(s, β) = |c(s, β) − s(s, β)| − |c(s, 0) − s(s, 0)| [m] (s: the shaped
// skin point, c: its skeleton correspondence, meshing::layer_geometry), which a taller or shorter body of the same
// build does not change (stature moves skin and skeleton together):
//   h   = 0.36 + 0.06 sin(5 y + 1) + kThicknessPerDepth d        (1 cm more flesh → h + 0.08)
//   Y_t = 7 kPa · exp(0.35 sin(4 x + 3 y)) · exp(−kStiffnessPerDepth d)   (1 cm more flesh → 45 % softer)
//   Y_n = 0.45 · Y_t · exp(0.25 cos(6 y))
// with (x, y) the template position [m], each clamped 2 % inside the parameter ranges. It lives on the
// vertices, not in the span of any control-point basis, so a fit cannot reproduce it exactly — as with
// real tissue — and recovered parameters can be compared with it.
// A user's truth (`--truth-model FILE.toml`, a shape model as `sflsh shapefit` writes): κ at its control points
// is the model's κ(β) (SFLSH eq. 1, clamped into its bounds, reduced::material_for_beta), carried to every region
// vertex by the basis φ of those control points on the layer, then clamped into the run's bounds.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/material/parameters.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace sflsh::validate {

inline constexpr double kThicknessPerDepth = 8.0;   ///< dh/dd [1/m] of the built-in truth
inline constexpr double kStiffnessPerDepth = 60.0;  ///< −d ln Y_t / dd [1/m] of the built-in truth

class TrueMaterial {
 public:
  TrueMaterial() = default;  ///< the built-in truth
  /// A user's truth: the shape model in `path` (errors name the file and field, as load_shape_model_file's).
  static TrueMaterial from_shape_model(const std::filesystem::path& path);

  /// κ per region vertex (R × 3, physical) of subject β, within `bounds`.
  material::KappaMatrix kappa_field(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                    const body::Betas& beta, const material::ParameterBounds& bounds) const;
  /// The formulas above as text (written beside the ground truth).
  std::string description() const;
  /// Identifies the truth in cached ground-truth cases: a case computed with another truth is recomputed.
  std::string fingerprint() const;
  bool builtin() const { return !shape_model_; }
  const std::optional<reduced::ShapeModelFile>& shape_model() const { return shape_model_; }

 private:
  std::optional<reduced::ShapeModelFile> shape_model_;
};

/// The built-in truth's κ per region vertex (R × 3, physical) of subject β.
material::KappaMatrix true_kappa_field(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                       const body::Betas& beta, const material::ParameterBounds& bounds);

/// The soft-tissue depth change d(s, β) of the built-in truth per region vertex [m].
Eigen::VectorXd soft_tissue_depth_change(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                         const body::Betas& beta);

}  // namespace sflsh::validate
