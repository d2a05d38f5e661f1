// sflsh mesh: the soft-tissue layer as a tet mesh, retargeted to a subject and thickness.
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/meshing/label_names.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/retarget.hpp>
#include <sflsh/meshing/subject_layer.hpp>

#include <chrono>
#include <map>

namespace sflsh::app {
namespace {

struct MeshOptions {
  SubjectOptions subject;
  double thickness = 0.5;
  std::string mesher = "cgal";
  std::string size = "default";
  std::string region = "torso,upper_arms,thighs";
  std::string cache;
  bool rebuild_cache = false;
  int threads = 2;
  std::string out;
};

Eigen::MatrixXd as_column(const std::vector<meshing::Part>& parts) {
  Eigen::MatrixXd column(static_cast<Eigen::Index>(parts.size()), 1);
  for (std::size_t i = 0; i < parts.size(); ++i) column(static_cast<Eigen::Index>(i)) = static_cast<double>(parts[i]);
  return column;
}

/// layer.vtu: the retargeted tets with node kind, part, thickness fraction and local thickness (carried in from the
/// skin), displacement from the mesh's own template, and per-tet quality.
void write_layer_volume(RunFolder& run, const meshing::SubjectLayer& subject) {
  const meshing::LayerMesh& mesh = *subject.mesh;
  const meshing::RetargetedLayer& layer = subject.layer;
  const auto& geometry = layer.geometry;
  Eigen::MatrixXd surface_fields(mesh.region_surface.num_vertices(), 2);
  surface_fields.col(0) = geometry.thickness;
  surface_fields.col(1) = geometry.thickness.cwiseProduct(geometry.max_thickness());
  const Eigen::MatrixXd node_fields = subject.retargeter->extend_surface_field(surface_fields);
  Eigen::MatrixXd kind(mesh.num_nodes(), 1);
  for (int i = 0; i < mesh.num_nodes(); ++i) kind(i) = static_cast<double>(mesh.kind[static_cast<std::size_t>(i)]);
  const meshing::TetQuality quality = meshing::tet_quality(layer.nodes, mesh.tets);
  vtk::Fields fields;
  fields.point_data.push_back({"node_kind", kind, true});
  fields.point_data.push_back({"part", as_column(mesh.node_part), true});
  fields.point_data.push_back({"thickness_fraction", node_fields.col(0), false});
  fields.point_data.push_back({"local_thickness", node_fields.col(1), false});
  fields.point_data.push_back({"displacement_from_template", layer.nodes - mesh.nodes, false});
  fields.cell_data.push_back({"part", as_column(mesh.tet_part), true});
  fields.cell_data.push_back({"volume", quality.volume, false});
  fields.cell_data.push_back({"min_dihedral_deg", quality.min_dihedral_deg, false});
  fields.cell_data.push_back({"radius_edge", quality.radius_edge, false});
  fields.labels.push_back({"part_names", meshing::part_names()});
  fields.labels.push_back({"node_kind_names", meshing::node_kind_names()});
  vtk::write_unstructured(run.stage("layer.vtu"), layer.nodes, mesh.tets, fields);
}

/// outer.vtp and inner.vtp: the skin and the layer's inner surface with thickness, part and the skeleton vector.
void write_layer_surfaces(RunFolder& run, const meshing::LayerMesh& mesh, const meshing::LayerGeometry& geometry) {
  vtk::Fields surface;
  surface.point_data.push_back({"thickness_fraction", geometry.thickness, false});
  surface.point_data.push_back(
      {"local_thickness", Eigen::MatrixXd(geometry.thickness.cwiseProduct(geometry.max_thickness())), false});
  surface.point_data.push_back({"max_thickness", geometry.max_thickness(), false});
  surface.point_data.push_back({"part", as_column(mesh.region_surface.part), true});
  surface.point_data.push_back({"to_skeleton", geometry.skeleton - geometry.skin, false});
  surface.labels.push_back({"part_names", meshing::part_names()});
  vtk::write_surface(run.stage("outer.vtp"), geometry.skin, mesh.region_surface.faces, surface);
  meshing::RowMatrixX3d inner = geometry.skin;
  for (int v = 0; v < inner.rows(); ++v)
    inner.row(v) += geometry.thickness(v) * (geometry.skeleton.row(v) - geometry.skin.row(v));  // docs/physics.md §1.4
  vtk::write_surface(run.stage("inner.vtp"), inner, mesh.region_surface.faces, surface);
}

/// summary.json's description of the layer: sizes, node kinds, the skin embedding's error, quality and remeshing.
void add_layer_summary(nlohmann::json& summary, const meshing::SubjectLayer& subject) {
  const meshing::LayerMesh& mesh = *subject.mesh;
  const meshing::RetargetedLayer& layer = subject.layer;
  std::map<std::string, long> kinds;
  for (auto k : mesh.kind)
    ++kinds[k == meshing::NodeKind::outer   ? "outer"
            : k == meshing::NodeKind::inner ? "inner"
            : k == meshing::NodeKind::side  ? "side"
                                            : "interior"];
  const meshing::RowMatrixX3d skin_points = mesh.skin_positions(layer.nodes);
  summary["region"] = mesh.region;
  summary["mesher"] = meshing::mesher_name(mesh.mesher);
  summary["size"] = meshing::size_preset_name(mesh.size);
  summary["edge_length_m"] = mesh.edge_length;
  summary["nodes"] = mesh.num_nodes();
  summary["tets"] = mesh.num_tets();
  summary["node_kinds"] = kinds;
  summary["skin_vertices"] = mesh.region_surface.num_vertices();
  summary["skin_mapping"] = mesh.skin.node.empty() || mesh.skin.node.front() < 0 ? "embedded" : "nodes";
  summary["skin_embedding_max_error_m"] = (skin_points - layer.geometry.skin).rowwise().norm().maxCoeff();
  summary["quality"] = layer.quality;
  // true: the template inverted tets at this shape and thickness, and the subject's own layer was meshed (cached)
  summary["remeshed"] = subject.remeshed;
  if (subject.remeshed) {
    summary["template_failure"] = subject.template_failure;
    summary["fallback"] = subject.fallback;
  }
}

void run_mesh(const MeshOptions& opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  require(opt.thickness > 0.0 && opt.thickness < 1.0, "--thickness {}: expected a fraction 0 < h < 1", opt.thickness);
  require(opt.threads >= 1, "--threads {}: expected at least 1", opt.threads);
  const body::BodyModel model = load_selected_body(opt.subject);
  std::string subject_label;
  const body::Betas beta = selected_betas(opt.subject, subject_label);
  if (subject_label.empty()) subject_label = "template";

  meshing::LayerMeshOptions options;
  options.region_names = meshing::parse_region_names(opt.region);
  options.mesher = meshing::parse_mesher(opt.mesher);
  options.size = meshing::parse_size_preset(opt.size);
  options.threads = opt.threads;
  const std::filesystem::path cache_dir =
      opt.cache.empty() ? meshing::default_cache_dir() : std::filesystem::path(opt.cache);
  meshing::CacheOutcome outcome{};
  const auto t_mesh = std::chrono::steady_clock::now();
  meshing::LayerMesh template_mesh = meshing::cached_layer_mesh(model, options, cache_dir, opt.rebuild_cache, &outcome);
  const double mesh_seconds = seconds_since(t_mesh);
  const double template_meshing_seconds = outcome == meshing::CacheOutcome::hit ? 0.0 : template_mesh.meshing_seconds;
  const meshing::LayerGeometry template_geometry =
      meshing::layer_geometry(model, template_mesh.region_surface, template_mesh.correspondence, body::Betas::Zero(),
                              template_mesh.template_thickness_field());
  const meshing::QualityReport template_quality =
      meshing::layer_quality(template_mesh, template_mesh.nodes, template_geometry);

  // The template retargeted, or the subject's own layer where that inverts tets (meshing/subject_layer.hpp).
  const auto t_factor = std::chrono::steady_clock::now();
  const Eigen::VectorXd thickness_field =
      Eigen::VectorXd::Constant(template_mesh.region_surface.num_vertices(), opt.thickness);
  const meshing::SubjectLayer subject =
      meshing::subject_layer(model, std::move(template_mesh), beta, thickness_field, options, cache_dir);
  const meshing::RetargetedLayer& layer = subject.layer;
  const double factor_seconds = seconds_since(t_factor) - layer.seconds;  // and the subject's meshing, if any

  RunFolder run(opt.out);
  write_layer_volume(run, subject);
  write_layer_surfaces(run, *subject.mesh, layer.geometry);
  nlohmann::json summary = summary_header("mesh", invocation.argc, invocation.argv);
  summary["body"] = body::body_label(opt.subject);
  summary["body_name"] = model.name;
  summary["subject"] = subject_label;
  summary["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  summary["thickness"] = opt.thickness;
  add_layer_summary(summary, subject);
  summary["cache"] = {{"path", meshing::layer_cache_path(cache_dir, model, options).string()},
                      {"outcome", meshing::cache_outcome_name(outcome)}};
  summary["quality_template"] = template_quality;
  summary["timings_s"] = {{"template_mesh", template_meshing_seconds},
                          {"template_load_or_build", mesh_seconds},
                          {"factorization", factor_seconds},
                          {"retarget", layer.seconds}};
  summary["files"] = {"layer.vtu", "outer.vtp", "inner.vtp"};
  write_summary(run, summary, seconds_since(t0), {.timings_s_total = true});
  run.commit();
  logger()->info("layer for {} (h = {}): {} tets, min dihedral {:.1f}°, retarget {:.3f} s → {}", subject_label,
                 opt.thickness, subject.mesh->num_tets(), layer.quality.min_dihedral_deg, layer.seconds, opt.out);
}

}  // namespace

void register_mesh_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<MeshOptions>();
  CLI::App* cmd = app.add_subcommand(
      "mesh", "Mesh the soft-tissue layer (cached template) and retarget it to a subject and thickness");
  add_body_option(*cmd, opt->subject);
  add_subject_options(*cmd, opt->subject);
  cmd->add_option("--thickness", opt->thickness, "Thickness fraction h of the layer, 0 < h < 1")->capture_default_str();
  add_mesher_option(*cmd, opt->mesher, "layered: extruded prisms, valid for any h");
  add_mesh_option(*cmd, opt->size, true, "coarse ~10k tets, default ~50k, fine ~200k");
  cmd->add_option("--region", opt->region, "Comma-separated parts: torso, upper_arms, thighs, left_upper_arm, …")
      ->capture_default_str();
  cmd->add_option("--cache", opt->cache, "Cache folder for template meshes (default $SFLSH_CACHE or ~/.cache/sflsh)");
  cmd->add_flag("--rebuild-cache", opt->rebuild_cache, "Remesh the template even when a cached mesh exists");
  cmd->add_option("--threads", opt->threads, "Threads for the mesher")->capture_default_str();
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] { run_mesh(*opt, invocation); });
}

}  // namespace sflsh::app
