#include <sflsh/core/error.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/model/layer_settings.hpp>
#include <sflsh/model/simulation_output.hpp>

namespace sflsh::model {

void check_layer_settings(const LayerSettings& s) {
  // The same physical ranges as a scene's [[body]] density and stiffness_scale (docs/scenes.md, "Input limits").
  require(s.density >= 1.0 && s.density <= 1e5, "--density: {} kg/m³ is outside [1, 100000] kg/m³", s.density);
  require(s.stiffness_scale >= 1e-3 && s.stiffness_scale <= 1e3, "--stiffness-scale: {} is outside [0.001, 1000]",
          s.stiffness_scale);
  parse_mass_kind(s.mass, "--mass");
}

std::optional<material::MaterialFile> load_layer_material(const LayerSettings& s) {
  if (s.material.empty()) return std::nullopt;
  return material::load_material_file(s.material);
}

BodyLayerOptions body_layer_options(const LayerSettings& s, const std::string& mesh) {
  BodyLayerOptions o;
  o.mesher = meshing::parse_mesher(s.mesher);
  o.size = meshing::parse_size_preset(mesh);
  if (!s.cache.empty()) o.cache_dir = s.cache;
  o.density = s.density;
  o.gravity = s.gravity;
  o.stiffness_scale = s.stiffness_scale;
  o.mass = parse_mass_kind(s.mass, "--mass");
  return o;
}

nlohmann::json material_summary(const LayerSettings& s, const std::optional<material::MaterialFile>& material) {
  return {{"file", s.material},
          {"control_points", material ? material->control_points.size() : static_cast<std::size_t>(s.control_points)},
          {"density", s.density},
          {"gravity", s.gravity},
          {"stiffness_scale", s.stiffness_scale}};
}

RowMatrixX3d region_normals(const BodyLayer& layer) {
  const RowMatrixX3d all = vertex_normals(layer.shaped, layer.model->faces);
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  RowMatrixX3d normals(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r) normals.row(static_cast<Eigen::Index>(r)) = all.row(region[r]);
  return normals;
}

}  // namespace sflsh::model
