// sflsh material show: the heterogeneous material fields of a subject's layer, for ParaView.
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/meshing/subject_layer.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <algorithm>
#include <chrono>

namespace sflsh::app {
namespace {

struct ShowOptions {
  SubjectOptions subject;
  std::string material;     ///< material file; empty: defaults at --control-points points
  std::string shape_model;  ///< shape model file: the material of the subject's β (SFLSH eq. 1)
  int control_points = 24;
  bool phi = false;
  std::string mesher = "cgal";
  std::string size = "default";
  std::string cache;
  std::string out;
};

/// thickness_fraction (also under its older name thickness), young_tangent, young_normal (docs/output.md).
void add_kappa_fields(std::vector<vtk::Field>& fields, const material::KappaMatrix& kappa) {
  fields.push_back({"thickness_fraction", kappa.col(0), false});
  for (int k = 0; k < material::kNumKappa; ++k)
    fields.push_back({std::string(material::kKappaNames[static_cast<std::size_t>(k)]), kappa.col(k), false});
}

void run_show(const ShowOptions& opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  require(opt.control_points >= 1, "--control-points {}: expected at least 1", opt.control_points);
  const body::BodyModel model = load_selected_body(opt.subject);
  std::string subject_label;
  const body::Betas beta = selected_betas(opt.subject, subject_label);
  if (subject_label.empty()) subject_label = "template";

  material::MaterialFile file;  // read first: a bad file fails before any meshing
  if (!opt.material.empty()) {
    file = material::load_material_file(opt.material);
    material::check_against_body(file, model);
  } else if (!opt.shape_model.empty()) {
    const reduced::ShapeModelFile shape_model = reduced::load_shape_model_file(opt.shape_model);
    reduced::check_layer_match(shape_model, meshing::region_key(meshing::default_region_names()), opt.size,
                               "--shape-model");
    file = reduced::material_for_beta(shape_model, model, beta, subject_label);
  }
  meshing::LayerMeshOptions mesh_options;
  mesh_options.mesher = meshing::parse_mesher(opt.mesher);
  mesh_options.size = meshing::parse_size_preset(opt.size);
  const std::filesystem::path cache_dir =
      opt.cache.empty() ? meshing::default_cache_dir() : std::filesystem::path(opt.cache);
  meshing::LayerMesh template_mesh = meshing::cached_layer_mesh(model, mesh_options, cache_dir);

  if (opt.material.empty() && opt.shape_model.empty())
    file = material::default_material(model, template_mesh, opt.control_points, subject_label);
  // `betas`: the shape the fields are drawn for, so that `sflsh shapefit` can read the file without a subject
  // table. A given material file keeps its own β; it gets the run's β only when it names the run's subject.
  if (opt.material.empty() || (!file.betas && file.subject == subject_label)) {
    file.betas.emplace();
    std::copy(beta.data(), beta.data() + beta.size(), file.betas->begin());
  }
  const material::BiharmonicBasis basis = material::layer_basis(model, template_mesh, file.vertices());
  const material::KappaMatrix kappa = file.kappa();
  const Eigen::VectorXd thickness = material::evaluate_field(basis.phi, kappa).col(0);
  // The template retargeted, or the subject's own layer where that inverts tets (meshing/subject_layer.hpp).
  const meshing::SubjectLayer subject =
      meshing::subject_layer(model, std::move(template_mesh), beta, thickness, mesh_options, cache_dir);
  const meshing::LayerMesh& mesh = *subject.mesh;
  const meshing::Retargeter& retargeter = *subject.retargeter;
  const meshing::RetargetedLayer& layer = subject.layer;
  const material::LayerMaterialFields fields =
      material::layer_material_fields(retargeter, basis.phi, kappa, layer.nodes);

  RunFolder run(opt.out);
  vtk::Fields surface;
  add_kappa_fields(surface.point_data, fields.vertex);
  if (opt.phi)
    for (int i = 0; i < basis.num_functions(); ++i)
      surface.point_data.push_back({fmt::format("phi_{:02d}", i), basis.phi.col(i), false});
  vtk::write_surface(run.stage("surface.vtp"), layer.geometry.skin, mesh.region_surface.faces, surface);

  vtk::Fields volume;
  add_kappa_fields(volume.point_data, fields.node);
  add_kappa_fields(volume.cell_data, fields.tet);
  volume.cell_data.push_back({"normal", fields.normal, false});
  vtk::write_unstructured(run.stage("layer.vtu"), layer.nodes, mesh.tets, volume);

  const int count = static_cast<int>(file.control_points.size());
  vtk::Points points(count, 3);
  Eigen::MatrixXd index(count, 1);
  for (int i = 0; i < count; ++i) {
    points.row(i) = layer.geometry.skin.row(
        mesh.region_surface
            .local_of[static_cast<std::size_t>(file.control_points[static_cast<std::size_t>(i)].vertex)]);
    index(i) = i;
  }
  vtk::Fields control;
  control.point_data.push_back({"index", index, true});
  add_kappa_fields(control.point_data, kappa);
  vtk::write_surface(run.stage("control_points.vtp"), points, vtk::Cells(0, 3), control);
  material::save_material_file(run.stage("material.toml"), file,
                               fmt::format("Material of {} written by `sflsh material show`", subject_label));

  nlohmann::json summary = summary_header("material show", invocation.argc, invocation.argv);
  summary["subject"] = subject_label;
  summary["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  summary["material"] = !opt.material.empty() ? opt.material : !opt.shape_model.empty() ? opt.shape_model : "defaults";
  summary["material_source"] = !opt.material.empty()      ? "material file"
                               : !opt.shape_model.empty() ? "shape model"
                                                          : "defaults";
  summary["control_points"] = count;
  summary["mesher"] = meshing::mesher_name(mesh.mesher);
  summary["tets"] = mesh.num_tets();
  summary["quality"] = layer.quality;
  nlohmann::json ranges;
  for (int k = 0; k < material::kNumKappa; ++k)
    ranges[std::string(material::kKappaNames[static_cast<std::size_t>(k)])] = {fields.tet.col(k).minCoeff(),
                                                                               fields.tet.col(k).maxCoeff()};
  summary["tet_ranges"] = ranges;
  summary["basis_active_set_iterations"] = basis.total_iterations();
  summary["files"] = {"surface.vtp", "layer.vtu", "control_points.vtp", "material.toml"};
  write_summary(run, summary, seconds_since(t0), {.wall_time_s = true});
  run.commit();
  logger()->info("material of {}: {} control points, {} tets → {}", subject_label, count, mesh.num_tets(), opt.out);
}

}  // namespace

void add_material_show_command(CLI::App& material, const Invocation& invocation) {
  auto opt = std::make_shared<ShowOptions>();
  CLI::App* cmd = material.add_subcommand(
      "show", "Write the material fields of a subject's layer: κ per skin vertex and tet, control points, φ_i");
  add_body_option(*cmd, opt->subject);
  add_subject_options(*cmd, opt->subject);
  CLI::Option* material_option = cmd->add_option(
      "--material", opt->material, "Material file (TOML); default: provisional defaults at --control-points points");
  cmd->add_option("--shape-model", opt->shape_model,
                  "Shape model file (TOML, e.g. data/shape_models/default.toml): the material of the subject's shape")
      ->excludes(material_option);
  cmd->add_option("--control-points", opt->control_points,
                  "Number of control points N when no --material is given (1, 12, 24, 84, …)")
      ->capture_default_str();
  cmd->add_flag("--phi", opt->phi, "Also write the basis functions φ_i as point data of surface.vtp");
  add_mesher_option(*cmd, opt->mesher);
  add_mesh_option(*cmd, opt->size, true);
  cmd->add_option("--cache", opt->cache, "Cache folder for template meshes (default $SFLSH_CACHE or ~/.cache/sflsh)");
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] { run_show(*opt, invocation); });
}

}  // namespace sflsh::app
