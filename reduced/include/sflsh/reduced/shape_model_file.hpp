#pragma once
// The shape-model file: a fitted shape-dependent elasticity κ̂_i(β) = A_iᵀβ + b_i (SFLSH eq. 1,
// shape_elasticity.hpp) with everything needed to turn it into any subject's material file
// (material_file.hpp): the body it belongs to, the control points (body template vertices and their
// positions, in the order of the fit), the uniform Poisson ratio and Fung saturation, the parameter
// bounds whose maxima normalize κ (parameters.hpp), the basis φ the control values are interpolated
// with, and how the model was fitted (regularizer, λ, subjects, motions; metadata only).
//
// Format: TOML, like material files, because the file is meant to be read and shipped
// (data/shape_models/default.toml): TOML has comments (a header says which command and commit produced a
// file; JSON has none), and toml++ keeps source lines, so every bad entry is reported as "<file>:<line>".
//
//   version = 1
//   body = "open_body"
//   poisson = 0.2
//   saturation = 4.0
//   [bounds]                                   # optional; defaults of ParameterBounds
//   thickness = [0.1, 0.6]
//   young_tangent = [500.0, 50000.0]           # Pa
//   young_normal = [500.0, 50000.0]            # Pa
//   [basis]                                    # φ of build_body_layer (material::layer_basis)
//   kind = "bounded_biharmonic"                # the only kind: 0 ≤ φ ≤ 1, Σφ = 1, Voronoi mass
//   region = "thighs+torso+upper_arms"         # optional: the layer region of the fit
//   mesh = "coarse"                            # optional: the layer mesh preset of the fit
//   [fit]                                      # optional metadata
//   regularizer = "local"                      # "l2" | "local" (eq. 7) | "none"
//   lambda = 1.0                               # λ of eq. 7, ≥ 0
//   subjects = ["OPEN_TRAIN_1", "OPEN_TRAIN_2"]
//   motions = ["running_on_spot"]
//   [[control_point]]
//   vertex = 1234                              # body template vertex index
//   position = [0.012, 0.345, 0.101]           # optional: template position [m], checked against the body
//   b = [0.5, 0.1, 0.04]                       # κ̂_i(0) = (h, Y_t, Y_n) / κ_max
//   A = [                                      # 10 rows (β_1 … β_10) of 3 (h, Y_t, Y_n): ∂κ̂_i/∂β
//     [0.0, 0.0, 0.0],
//     ...
//   ]
//
// Every problem (missing or unknown key, wrong type or size, non-finite number, repeated vertex, TOML
// syntax) is a one-line sflsh::Error "<file>:<line>: <what>" naming the field.
#include <sflsh/body/body_model.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/reduced/shape_elasticity.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::reduced {

inline constexpr int kShapeModelFileVersion = 1;
/// The only basis kind: material::layer_basis (bounded biharmonic, rows normalized, Voronoi mass).
inline constexpr std::string_view kShapeModelBasisKind = "bounded_biharmonic";

struct ShapeModelControlPoint {
  int vertex = -1;                                    ///< body template vertex index
  std::optional<Eigen::Vector3d> position;            ///< template position of that vertex [m], for checking
  ShapeMatrix A = ShapeMatrix::Zero();                ///< A_i (10×3): normalized κ̂ per unit β (eq. 1)
  Eigen::RowVector3d b = Eigen::RowVector3d::Zero();  ///< b_i: normalized κ̂ at β = 0 (h, Y_t, Y_n)
  int line = 0;                                       ///< source line when read from a file (0 otherwise)
};

/// How the model was fitted (metadata; not needed to evaluate it).
struct ShapeModelFit {
  Regularizer regularizer = Regularizer::local;
  double lambda = 0.0;                ///< λ of eq. 7
  std::vector<std::string> subjects;  ///< train subjects
  std::vector<std::string> motions;   ///< train motions
};

struct ShapeModelFile {
  std::string body;                  ///< body model name (body::BodyModel::name)
  double poisson = 0.2;              ///< ν ∈ (−1, ½), uniform (SFLSH §3)
  double saturation = 4.0;           ///< Fung saturation s > 0, uniform (SFLSH §3)
  material::ParameterBounds bounds;  ///< κ ranges; their maxima normalize κ (κ̂ = κ / κ_max)
  std::string region;                ///< layer region of the fit, a meshing::region_key (empty: not recorded)
  std::string mesh;  ///< layer mesh size preset of the fit: coarse | default | fine (empty: not recorded)
  std::optional<ShapeModelFit> fit;
  std::vector<ShapeModelControlPoint> control_points;
  std::string source;  ///< the file it was read from (load_shape_model_file); empty in memory
  int basis_line = 0;  ///< line of [basis] in `source` (0: not read from a file)

  int num_controls() const { return static_cast<int>(control_points.size()); }
  std::vector<int> vertices() const;   ///< control vertices, in file order
  ShapeElasticity elasticity() const;  ///< (A_i, b_i) in file order
};

/// A shape-model file for `elasticity` on `control_vertices` (body vertex indices, the order of
/// elasticity's rows) with positions from `model`'s template, `bounds` and ν, s; no fit metadata.
ShapeModelFile make_shape_model_file(const ShapeElasticity& elasticity, const body::BodyModel& model,
                                     const std::vector<int>& control_vertices, const material::ParameterBounds& bounds,
                                     double poisson = 0.2, double saturation = 4.0);

/// Reads and validates a shape-model file (see above). Errors: "<file>:<line>: …" naming the field.
ShapeModelFile load_shape_model_file(const std::filesystem::path& path);

/// Writes the file atomically after validate(); numbers as shortest round-trip decimals, so loading
/// gives back identical A_i, b_i. `header` becomes a leading comment block (one "# " line per line).
void save_shape_model_file(const std::filesystem::path& path, const ShapeModelFile& model,
                           const std::string& header = "");

/// Throws unless a shape model recorded with `region` and `mesh` (when it records them) fits layers of region
/// `layer_region` (a meshing::region_key) and mesh preset `layer_mesh`: "<file>:<line>: region in [basis]: …".
void check_layer_match(const ShapeModelFile& model, const std::string& layer_region, const std::string& layer_mesh,
                       std::string_view user);

/// Checks the body name non-empty, ν ∈ (−1, ½), 0 < s ≤ material::kSaturationMax, the bounds, at least one control
/// point, vertices ≥ 0 and distinct, every number finite, λ ≥ 0. Messages start with `what` (load passes
/// "<file>:<line>").
void validate(const ShapeModelFile& model, std::string_view what = "shape model");

/// The shipped shape model, data/shape_models/default.toml (body::data_dir(); $SFLSH_DATA overrides): the
/// local-regularizer full fit of `sflsh validate --preset quick` on the open body (coarse mesh, N = 4).
std::filesystem::path default_shape_model_path();

/// The material of a subject of shape β (SFLSH §4): κ̂_i(β) = A_iᵀβ + b_i (eq. 1), clamped into the
/// normalized bounds (clamp_normalized, as the fit does), de-normalized (κ = κ̂ κ_max) — a material file
/// build_body_layer accepts: the model's body, ν, s and bounds, one control point per model control
/// point with its template position. `subject` empty: "beta". Throws when the model names another body
/// or its control points do not match `body`'s template (material::check_against_body).
/// @param[in] model  shape model
/// @param[in] body   the body model the material is for (its name must equal model.body)
/// @param[in] beta   10 shape coefficients
material::MaterialFile material_for_beta(const ShapeModelFile& model, const body::BodyModel& body,
                                         const body::Betas& beta, const std::string& subject = "");

}  // namespace sflsh::reduced
