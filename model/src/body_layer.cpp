#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/subject_layer.hpp>
#include <sflsh/meshing/tet_backend.hpp>
#include <sflsh/model/body_layer.hpp>

namespace sflsh::model {

namespace {

/// Pose-corrective directions at every node (3N × 207): the skin's posedirs carried into the volume by
/// the retargeter's harmonic extension and faded linearly with depth, so the bones see none (docs/physics.md §5).
Eigen::MatrixXd node_pose_directions(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                     const meshing::Retargeter& retargeter, const Eigen::VectorXd& depth) {
  if (!model.has_pose_correctives()) return {};
  const int regions = mesh.region_surface.num_vertices();
  Eigen::MatrixXd per_vertex(regions, 3 * body::kNumPoseFeatures);
  for (int r = 0; r < regions; ++r) {
    const int v = mesh.region_surface.vertices[static_cast<std::size_t>(r)];
    for (int c = 0; c < 3; ++c)
      per_vertex.row(r).segment(c * body::kNumPoseFeatures, body::kNumPoseFeatures) = model.posedirs.row(3 * v + c);
  }
  const Eigen::MatrixXd per_node = retargeter.extend_surface_field(per_vertex);
  Eigen::MatrixXd dirs(3 * mesh.num_nodes(), body::kNumPoseFeatures);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const double fade = std::clamp(1.0 - depth[i], 0.0, 1.0);
    for (int c = 0; c < 3; ++c)
      dirs.row(3 * i + c) = fade * per_node.row(i).segment(c * body::kNumPoseFeatures, body::kNumPoseFeatures);
  }
  return dirs;
}

}  // namespace

BodyLayer build_body_layer(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion,
                           const material::MaterialFile* material, int control_points,
                           const BodyLayerOptions& options) {
  require(options.density > 0.0 && std::isfinite(options.density), "body layer: density must be positive, got {}",
          options.density);
  require(options.stiffness_scale > 0.0 && std::isfinite(options.stiffness_scale),
          "body layer: stiffness scale must be positive, got {}", options.stiffness_scale);
  require(beta.allFinite(), "body layer: β has non-finite entries");
  BodyLayer out;
  out.model = &model;
  out.beta = beta;
  meshing::LayerMeshOptions mesh_options;
  mesh_options.mesher = options.mesher;
  mesh_options.size = options.size;
  const std::filesystem::path cache_dir = options.cache_dir.empty() ? meshing::default_cache_dir() : options.cache_dir;
  meshing::LayerMesh template_mesh = meshing::cached_layer_mesh(model, mesh_options, cache_dir);

  if (material) {
    material::check_against_body(*material, model);
    out.material = *material;
  } else {
    require(control_points >= 1, "body layer: --control-points must be at least 1, got {}", control_points);
    out.material = material::default_material(model, template_mesh, control_points, "");
  }
  // φ over the region's vertices, from the template (the material's control points live on it).
  const material::BiharmonicBasis basis = material::layer_basis(model, template_mesh, out.material.vertices());
  const material::KappaMatrix kappa = out.material.kappa();
  const Eigen::VectorXd thickness = material::evaluate_field(basis.phi, kappa).col(0);
  meshing::SubjectLayer subject;
  try {
    subject = meshing::subject_layer(model, std::move(template_mesh), beta, thickness, mesh_options, cache_dir);
  } catch (const Error& e) {
    if (!material) throw;
    // A material file's thickness the template cannot be retargeted to: name the file and its thickest point.
    std::size_t thickest = 0;
    for (std::size_t i = 1; i < material->control_points.size(); ++i)
      if (material->control_points[i].kappa.thickness > material->control_points[thickest].kappa.thickness)
        thickest = i;
    const material::MaterialControlPoint& p = material->control_points[thickest];
    const std::string file = material->source.empty() ? std::string("material") : material->source;
    throw_error(
        "{}{}: thickness: up to {:.3g} (control_point #{}) is more than the {} {} layer reaches for this shape, "
        "retargeted or meshed on the subject itself ({}); lower the thickness or use a finer --mesh or another "
        "--mesher (docs/meshing.md, \"Every mesher at every thickness\")",
        file, p.line > 0 ? fmt::format(":{}", p.line) : std::string(), p.kappa.thickness, thickest,
        meshing::mesher_name(options.mesher), meshing::size_preset_name(options.size), e.what());
  }
  out.layer = std::move(subject.layer);
  out.remeshed = subject.remeshed;
  out.fallback = subject.fallback;
  out.mesh = std::move(subject.mesh);
  const meshing::LayerMesh& mesh = *out.mesh;
  const meshing::Retargeter& retargeter = *subject.retargeter;
  out.fields = material::layer_material_fields(retargeter, basis.phi, kappa, out.layer.nodes);
  out.depth = retargeter.depth();
  out.shaped = body::shaped_template(model, beta);

  // Skinning weights of the nodes: the region vertices' weights carried inside like any surface field.
  Eigen::MatrixXd vertex_weights(mesh.region_surface.num_vertices(), body::kNumJoints);
  for (int r = 0; r < mesh.region_surface.num_vertices(); ++r)
    vertex_weights.row(r) = model.weights.row(mesh.region_surface.vertices[static_cast<std::size_t>(r)]);
  auto weights = sparse_blend_weights(retargeter.extend_surface_field(vertex_weights));
  out.curve = std::make_shared<MotionCurve>(model, beta, motion);
  out.trajectory = std::make_shared<SkinnedTrajectory>(out.curve, std::move(weights),
                                                       node_pose_directions(model, mesh, retargeter, out.depth));

  Problem& p = out.problem;
  p.rest = out.layer.nodes;
  p.tets = mesh.tets;
  p.tet_material.resize(static_cast<std::size_t>(mesh.num_tets()));
  for (int e = 0; e < mesh.num_tets(); ++e) {
    material::SkinMaterial m;
    m.young_tangent = options.stiffness_scale * out.fields.tet(e, 1);
    m.young_normal = options.stiffness_scale * out.fields.tet(e, 2);
    m.poisson = out.material.poisson;
    m.saturation = out.material.saturation;
    m.overflow = options.overflow;
    p.tet_material[static_cast<std::size_t>(e)] =
        material::make_orthotropic_fung(m, out.fields.normal.row(e).transpose());
  }
  p.density = options.density;
  p.mass = lumped_masses(p.rest, p.tets, options.density);
  p.mass_kind = options.mass;
  if (options.gravity) p.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  // Inner nodes ride on the bones; the side wall and the skin's rim (its top edge) follow the skinned body:
  // zero elastic displacement, so the skin is continuous with the skinned body outside the region.
  for (meshing::NodeKind kind : {meshing::NodeKind::inner, meshing::NodeKind::side})
    for (int v : mesh.nodes_of_kind(kind)) p.dirichlet.add(v, 0b111u);
  for (int v : mesh.rim_nodes()) p.dirichlet.add(v, 0b111u);
  p.trajectory = out.trajectory;
  p.validate();
  out.rest_skin = mesh.skin_positions(p.rest);
  out.vertex_weights.resize(static_cast<std::size_t>(model.num_vertices()));
  for (Eigen::Index v = 0; v < model.num_vertices(); ++v)
    for (int k = 0; k < body::kNumJoints; ++k)
      if (model.weights(v, k) != 0.0)
        out.vertex_weights[static_cast<std::size_t>(v)].emplace_back(k, model.weights(v, k));
  return out;
}

RowMatrixX3d BodyLayer::surface_displacement(const Eigen::VectorXd& x) const {
  require(x.size() == problem.num_dofs(), "body layer: state has {} entries, expected {}", x.size(),
          problem.num_dofs());
  const Eigen::Map<const RowMatrixX3d> nodes(x.data(), problem.num_nodes(), 3);
  return mesh->skin_positions(nodes) - (rest_skin.rows() ? rest_skin : mesh->skin_positions(problem.rest));
}

RowMatrixX3d BodyLayer::posed_surface(const Eigen::VectorXd& x, double t) const {
  return posed_surface_from_displacement(surface_displacement(x), t);
}

RowMatrixX3d BodyLayer::posed_surface_from_displacement(const RowMatrixX3d& u, double t) const {
  require(u.rows() == mesh->region_surface.num_vertices(), "body layer: {} displacements for {} region vertices",
          u.rows(), mesh->region_surface.num_vertices());
  JointTransforms m;
  curve->transforms(t, m);
  RowMatrixX3d unposed = shaped;
  if (model->has_pose_correctives()) {
    PoseFeatures f;
    curve->features(t, f);
    const Eigen::VectorXd offsets = model->posedirs * f;
    unposed += Eigen::Map<const RowMatrixX3d>(offsets.data(), shaped.rows(), 3);
  }
  const std::vector<int>& region = mesh->region_surface.vertices;
  for (std::size_t r = 0; r < region.size(); ++r) unposed.row(region[r]) += u.row(static_cast<Eigen::Index>(r));
  RowMatrixX3d posed(unposed.rows(), 3);
  const bool sparse = static_cast<Eigen::Index>(vertex_weights.size()) == unposed.rows();
  for (Eigen::Index v = 0; v < unposed.rows(); ++v) {
    Matrix34d blend = Matrix34d::Zero();
    if (sparse) {
      for (const auto& [k, w] : vertex_weights[static_cast<std::size_t>(v)])
        blend += w * m[static_cast<std::size_t>(k)];
    } else {
      for (int k = 0; k < body::kNumJoints; ++k) {
        const double w = model->weights(v, k);
        if (w != 0.0) blend += w * m[static_cast<std::size_t>(k)];
      }
    }
    posed.row(v) = (blend.leftCols<3>() * unposed.row(v).transpose() + blend.col(3)).transpose();
  }
  return posed;
}

}  // namespace sflsh::model
