// Heterogeneous material fields on the layer mesh (docs/architecture.md §4).
#include <sflsh/core/error.hpp>
#include <sflsh/material/control_points.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/through_thickness.hpp>

namespace sflsh::material {

meshing::RowMatrixX3d region_positions(const body::BodyModel& model, const meshing::LayerMesh& mesh) {
  const auto& region = mesh.region_surface;
  meshing::RowMatrixX3d V(region.num_vertices(), 3);
  for (int v = 0; v < region.num_vertices(); ++v)
    V.row(v) = model.v_template.row(region.vertices[static_cast<std::size_t>(v)]);
  return V;
}

std::vector<int> region_mirror_map(const meshing::LayerMesh& mesh, const body::BodyModel& model, double tolerance) {
  const meshing::RowMatrixX3d V = region_positions(model, mesh);
  std::vector<int> mirror(static_cast<std::size_t>(V.rows()), -1);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::RowVector3d target(-V(v, 0), V(v, 1), V(v, 2));
    Eigen::Index best = 0;
    const double distance = (V.rowwise() - target).rowwise().squaredNorm().minCoeff(&best);
    if (distance <= tolerance * tolerance) mirror[static_cast<std::size_t>(v)] = static_cast<int>(best);
  }
  // Keep only consistent pairs (v ↔ w).
  for (std::size_t v = 0; v < mirror.size(); ++v)
    if (mirror[v] >= 0 && mirror[static_cast<std::size_t>(mirror[v])] != static_cast<int>(v)) mirror[v] = -1;
  return mirror;
}

std::vector<int> layer_control_points(const body::BodyModel& model, const meshing::LayerMesh& mesh, int count) {
  const auto& region = mesh.region_surface;
  ControlPointOptions options;
  options.density = Eigen::VectorXd::Ones(region.num_vertices());
  options.part.resize(static_cast<std::size_t>(region.num_vertices()));
  for (int v = 0; v < region.num_vertices(); ++v) {
    const auto part = region.part[static_cast<std::size_t>(v)];
    options.part[static_cast<std::size_t>(v)] = static_cast<int>(part);
    if (part == meshing::Part::torso) options.density(v) = kTorsoDensity;
  }
  options.mirror = region_mirror_map(mesh, model);
  const std::vector<int> local = place_control_points(region_positions(model, mesh), region.faces, count, options);
  std::vector<int> body_vertices;
  for (int v : local) body_vertices.push_back(region.vertices[static_cast<std::size_t>(v)]);
  return body_vertices;
}

BiharmonicBasis layer_basis(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                            const std::vector<int>& control_body_vertices) {
  const auto& region = mesh.region_surface;
  std::vector<int> local;
  for (int v : control_body_vertices) {
    require(v >= 0 && v < static_cast<int>(region.local_of.size()) && region.local_of[static_cast<std::size_t>(v)] >= 0,
            "control point at body vertex {} is not on the layer's region '{}'", v, mesh.region);
    local.push_back(region.local_of[static_cast<std::size_t>(v)]);
  }
  return biharmonic_basis(region_positions(model, mesh), region.faces, local);
}

Kappa default_kappa() {
  Kappa kappa;
  kappa.thickness = 0.5;
  kappa.young_tangent = 5000.0;
  kappa.young_normal = 2000.0;
  return kappa;
}

MaterialFile default_material(const body::BodyModel& model, const meshing::LayerMesh& mesh, int count,
                              const std::string& subject) {
  MaterialFile file;
  file.body = model.name;
  file.subject = subject;
  for (int v : layer_control_points(model, mesh, count)) {
    MaterialControlPoint point;
    point.vertex = v;
    point.position = model.v_template.row(v).transpose();
    point.kappa = default_kappa();
    file.control_points.push_back(point);
  }
  return file;
}

LayerMaterialFields layer_material_fields(const meshing::Retargeter& retargeter, const Eigen::MatrixXd& phi,
                                          const KappaMatrix& kappa_control, const meshing::RowMatrixX3d& nodes) {
  const meshing::LayerMesh& mesh = retargeter.mesh();
  require(phi.rows() == mesh.region_surface.num_vertices() && phi.cols() == kappa_control.rows(),
          "material fields: basis is {}×{}, expected {} region vertices × {} control points", phi.rows(), phi.cols(),
          mesh.region_surface.num_vertices(), kappa_control.rows());
  return layer_material_fields(retargeter, evaluate_field(phi, kappa_control), nodes);  // κ(s) = Σ φ_i(s) κ_i
}

LayerMaterialFields layer_material_fields(const meshing::Retargeter& retargeter, const KappaMatrix& kappa_vertex,
                                          const meshing::RowMatrixX3d& nodes) {
  const meshing::LayerMesh& mesh = retargeter.mesh();
  require(kappa_vertex.rows() == mesh.region_surface.num_vertices(),
          "material fields: {} vertex values for {} region vertices", kappa_vertex.rows(),
          mesh.region_surface.num_vertices());
  LayerMaterialFields fields;
  fields.vertex = kappa_vertex;
  fields.node = retargeter.extend_surface_field(fields.vertex);
  fields.tet.resize(mesh.num_tets(), kNumKappa);
  for (int e = 0; e < mesh.num_tets(); ++e) {
    fields.tet.row(e).setZero();
    for (int c = 0; c < 4; ++c) fields.tet.row(e) += 0.25 * fields.node.row(mesh.tets(e, c));
  }
  fields.normal = through_thickness_normals(nodes, mesh.tets, retargeter.depth());
  return fields;
}

}  // namespace sflsh::material
