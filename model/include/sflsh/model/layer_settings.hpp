#pragma once
// The settings of a subject's soft-tissue layer as a user gives them (mesher, material file, control points,
// cache, density, gravity, stiffness scale, mass) and what they turn into: BodyLayerOptions at a resolution, the
// material file, summary.json's "material" block. The command line (--mesher, --material, …) and the Python
// module share this one definition; the messages name the command-line options.
#include <sflsh/material/material_file.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/mass.hpp>

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace sflsh::model {

/// Material control points without a material file, and the soft tissue's density [kg/m³], wherever a layer is
/// described (the command line, Python, a scene's [[body]]).
inline constexpr int kDefaultControlPoints = 12;
inline constexpr double kDefaultDensity = 1000.0;

/// The layer's mesher and material (the resolution is chosen per run).
struct LayerSettings {
  std::string mesher = "layered";
  std::string material;  ///< TOML path; empty: the project defaults at control_points
  int control_points = kDefaultControlPoints;
  std::string cache;                 ///< empty: $SFLSH_CACHE or ~/.cache/sflsh
  double density = kDefaultDensity;  ///< [kg/m³]
  bool gravity = false;
  double stiffness_scale = 1.0;  ///< multiplies Y_t and Y_n
  /// lumped | consistent (mass.hpp); consistent unless told (kDefaultMassKind; the paper's: lumped)
  std::string mass = std::string(to_string(kDefaultMassKind));
};

/// Throws a one-line sflsh::Error for a non-positive density or stiffness scale or an unknown mass kind.
void check_layer_settings(const LayerSettings& settings);
/// The material file of settings.material, or nothing (the defaults).
std::optional<material::MaterialFile> load_layer_material(const LayerSettings& settings);
/// Layer options at resolution `mesh` ("coarse" | "default" | "fine").
BodyLayerOptions body_layer_options(const LayerSettings& settings, const std::string& mesh);
/// summary.json's "material" block.
nlohmann::json material_summary(const LayerSettings& settings, const std::optional<material::MaterialFile>& material);

/// Unit normals (R×3) of the shaped body at the region's vertices, for DynamicsAmplitude.
RowMatrixX3d region_normals(const BodyLayer& layer);

}  // namespace sflsh::model
