#include "layer_setup.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/meshing/layer_cache.hpp>

namespace sflsh::app {

void add_layer_options(CLI::App& cmd, LayerSettings& s) {
  cmd.add_option("--mesher", s.mesher, "Layer mesher: layered | cgal | gmsh")->check(CLI::IsMember({"layered", "cgal", "gmsh"}));
  cmd.add_option("--material", s.material, "Material file (TOML); default: the project defaults at --control-points");
  cmd.add_option("--control-points", s.control_points, "Control points N when no --material is given");
  cmd.add_option("--cache", s.cache, "Cache folder for template meshes and reduced models (default $SFLSH_CACHE or ~/.cache/sflsh)");
  cmd.add_option("--density", s.density, "Tissue density [kg/m³]");
  cmd.add_flag("--gravity", s.gravity, "Apply gravity");
  cmd.add_option("--stiffness-scale", s.stiffness_scale, "Multiply Y_t and Y_n by this factor");
}

void add_mass_option(CLI::App& cmd, LayerSettings& s) {
  cmd.add_option("--mass", s.mass,
                 "Inertia: lumped (default; ρV/4 per node) | consistent (ρV/20 (1 + δ_ab) per tet node pair); "
                 "docs/integrators.md");
}

void check_layer_settings(const LayerSettings& s) {
  // The same physical ranges as a scene's [[body]] density and stiffness_scale (docs/scenes.md, "Input limits").
  require(s.density >= 1.0 && s.density <= 1e5, "--density: {} kg/m³ is outside [1, 100000] kg/m³", s.density);
  require(s.stiffness_scale >= 1e-3 && s.stiffness_scale <= 1e3, "--stiffness-scale: {} is outside [0.001, 1000]",
          s.stiffness_scale);
  model::parse_mass_kind(s.mass, "--mass");
}

std::optional<material::MaterialFile> load_layer_material(const LayerSettings& s) {
  if (s.material.empty()) return std::nullopt;
  return material::load_material_file(s.material);
}

model::BodyLayerOptions body_layer_options(const LayerSettings& s, const std::string& mesh) {
  model::BodyLayerOptions o;
  o.mesher = meshing::parse_mesher(s.mesher);
  o.size = meshing::parse_size_preset(mesh);
  if (!s.cache.empty()) o.cache_dir = s.cache;
  o.density = s.density;
  o.gravity = s.gravity;
  o.stiffness_scale = s.stiffness_scale;
  o.mass = model::parse_mass_kind(s.mass, "--mass");
  return o;
}

nlohmann::json material_summary(const LayerSettings& s, const std::optional<material::MaterialFile>& material) {
  return {{"file", s.material},
          {"control_points", material ? material->control_points.size() : static_cast<std::size_t>(s.control_points)},
          {"density", s.density},
          {"gravity", s.gravity},
          {"stiffness_scale", s.stiffness_scale}};
}

void add_reduced_options(CLI::App& cmd, ReducedSettings& s) {
  cmd.add_option("--cubature-weights", s.cubature_weights, "nnls (training-free force matching) | voronoi")
      ->check(CLI::IsMember({"nnls", "voronoi"}));
  cmd.add_flag("--affine", s.affine, "Affine point handles (12 coordinates each instead of 3)");
}

reduced::ReducedModelOptions reduced_model_options(const ReducedSettings& s, int handles, int cubature, const std::string& cache) {
  reduced::ReducedModelOptions o;
  o.point_handles = handles;
  o.cubature = cubature;
  o.weighting = s.cubature_weights == "voronoi" ? reduced::CubatureWeighting::voronoi : reduced::CubatureWeighting::nnls;
  o.basis.affine = s.affine;
  if (!cache.empty()) o.cache_dir = cache;
  return o;
}

void check_handle_counts(const model::BodyLayer& layer, const std::vector<int>& handles) {
  const int most = reduced::max_point_handles(layer);
  for (int h : handles) require(h <= most, "reduced: {} point handles requested; the layer allows 1 to {}", h, most);
}

model::RowMatrixX3d region_normals(const model::BodyLayer& layer) {
  const model::RowMatrixX3d all = model::vertex_normals(layer.shaped, layer.model->faces);
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  model::RowMatrixX3d normals(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r) normals.row(static_cast<Eigen::Index>(r)) = all.row(region[r]);
  return normals;
}

}  // namespace sflsh::app
