#pragma once
// What the commands that build a subject's soft-tissue layer and reduced models on it share (simulate,
// compare, tradeoff): the layer options on the command line, the reduced-model options, the region normals for
// σ and a wall clock.
#include <sflsh/model/body_layer.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/reduced/reduced_model.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <optional>
#include <string>

namespace sflsh::app {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The layer's mesher and material (the resolution is chosen per command).
struct LayerSettings {
  std::string mesher = "layered";
  std::string material;                 ///< TOML path; empty: the project defaults at control_points
  int control_points = 12;
  std::string cache;                    ///< empty: $SFLSH_CACHE or ~/.cache/sflsh
  double density = 1000.0;              ///< [kg/m³]
  bool gravity = false;
  double stiffness_scale = 1.0;         ///< multiplies Y_t and Y_n
  std::string mass = "lumped";          ///< lumped | consistent (model/mass.hpp)
};
/// --mesher, --material, --control-points, --cache, --density, --gravity, --stiffness-scale.
void add_layer_options(CLI::App& cmd, LayerSettings& settings);
/// --mass lumped|consistent (the commands that choose the inertia; the others keep lumped).
void add_mass_option(CLI::App& cmd, LayerSettings& settings);
/// Throws a one-line sflsh::Error for a non-positive density or stiffness scale or an unknown mass kind.
void check_layer_settings(const LayerSettings& settings);
/// The material file of --material, or nothing (the defaults).
std::optional<material::MaterialFile> load_layer_material(const LayerSettings& settings);
/// Layer options at resolution `mesh` ("coarse" | "default" | "fine").
model::BodyLayerOptions body_layer_options(const LayerSettings& settings, const std::string& mesh);
/// summary.json's "material" block.
nlohmann::json material_summary(const LayerSettings& settings, const std::optional<material::MaterialFile>& material);

/// The reduced-model options that do not change along a sweep.
struct ReducedSettings {
  std::string cubature_weights = "nnls";   ///< nnls | voronoi
  bool affine = false;
};
/// --cubature-weights, --affine.
void add_reduced_options(CLI::App& cmd, ReducedSettings& settings);
/// Options of one reduced model: `handles` point handles, `cubature` tets (0 = every tet).
reduced::ReducedModelOptions reduced_model_options(const ReducedSettings& settings, int handles, int cubature, const std::string& cache);
/// Throws a one-line error naming the largest count when a handle count exceeds what the layer allows.
void check_handle_counts(const model::BodyLayer& layer, const std::vector<int>& handles);

/// Unit normals (R×3) of the shaped body at the region's vertices, for model::DynamicsAmplitude.
model::RowMatrixX3d region_normals(const model::BodyLayer& layer);

}  // namespace sflsh::app
