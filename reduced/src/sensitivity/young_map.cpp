// The control-point → cubature-tet map of the Young moduli and the q → skin map (young_map.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/reduced/young_map.hpp>

#include <algorithm>
#include <vector>

namespace sflsh::reduced {

Eigen::MatrixXd young_tet_map(const meshing::Retargeter& retargeter, const Eigen::MatrixXd& phi,
                              const std::vector<int>& tets, double stiffness_scale) {
  const meshing::LayerMesh& mesh = retargeter.mesh();
  require(phi.rows() == mesh.region_surface.num_vertices(), "young map: basis has {} rows, expected {} region vertices",
          phi.rows(), mesh.region_surface.num_vertices());
  require(stiffness_scale > 0.0 && std::isfinite(stiffness_scale),
          "young map: stiffness scale must be positive, got {}", stiffness_scale);
  // X φ: every basis function carried to the nodes, as layer_material_fields carries κ (it is linear in κ).
  const Eigen::MatrixXd node_basis = retargeter.extend_surface_field(phi);
  Eigen::MatrixXd W(static_cast<Eigen::Index>(tets.size()), phi.cols());
  for (std::size_t k = 0; k < tets.size(); ++k) {
    const int e = tets[k];
    require(e >= 0 && e < mesh.num_tets(), "young map: tet {} out of range [0, {})", e, mesh.num_tets());
    auto row = W.row(static_cast<Eigen::Index>(k));
    row.setZero();
    for (int c = 0; c < 4; ++c) row += 0.25 * node_basis.row(mesh.tets(e, c));  // κ_tet = mean of its nodes
    row *= stiffness_scale;
  }
  return W;
}

LayerYoungMap::LayerYoungMap(const model::BodyLayer& layer, double stiffness_scale)
    : layer_(layer),
      stiffness_scale_(stiffness_scale),
      phi_(material::layer_basis(*layer.model, *layer.mesh, layer.material.vertices()).phi),
      retargeter_(*layer.model, *layer.mesh) {
  require(layer.model && layer.mesh, "young map: the body layer has no body model or mesh");
  require(stiffness_scale > 0.0 && std::isfinite(stiffness_scale),
          "young map: stiffness scale must be positive, got {}", stiffness_scale);
}

Eigen::MatrixXd LayerYoungMap::tet_map(const std::vector<int>& tets) const {
  return young_tet_map(retargeter_, phi_, tets, stiffness_scale_);
}

Eigen::MatrixX2d LayerYoungMap::control_young() const {
  const material::KappaMatrix kappa = layer_.material.kappa();
  Eigen::MatrixX2d young(kappa.rows(), 2);
  young.col(0) = kappa.col(material::kYoungTangent);
  young.col(1) = kappa.col(material::kYoungNormal);
  return young;
}

void LayerYoungMap::set_control_young(const Eigen::MatrixX2d& young, model::Problem& problem) const {
  require(young.rows() == num_controls(), "young map: {} control moduli, expected {}", young.rows(), num_controls());
  require(young.allFinite() && young.minCoeff() > 0.0, "young map: control moduli must be finite and positive");
  require(problem.num_tets() == layer_.mesh->num_tets() &&
              problem.tet_material.size() == static_cast<std::size_t>(problem.num_tets()),
          "young map: the problem has {} tets, the layer {}", problem.num_tets(), layer_.mesh->num_tets());
  material::KappaMatrix kappa = layer_.material.kappa();
  kappa.col(material::kYoungTangent) = young.col(0);
  kappa.col(material::kYoungNormal) = young.col(1);
  const material::LayerMaterialFields fields =
      material::layer_material_fields(retargeter_, phi_, kappa, layer_.layer.nodes);
  for (int e = 0; e < problem.num_tets(); ++e) {
    material::SkinMaterial m;  // as build_body_layer makes it
    m.young_tangent = stiffness_scale_ * fields.tet(e, material::kYoungTangent);
    m.young_normal = stiffness_scale_ * fields.tet(e, material::kYoungNormal);
    m.poisson = layer_.material.poisson;
    m.saturation = layer_.material.saturation;
    m.overflow = problem.tet_material[static_cast<std::size_t>(e)].overflow;
    problem.tet_material[static_cast<std::size_t>(e)] =
        material::make_orthotropic_fung(m, fields.normal.row(e).transpose());
  }
}

SkinDisplacementMap::SkinDisplacementMap(const model::BodyLayer& layer, const Subspace& subspace)
    : layer_(layer), subspace_(subspace) {
  require(subspace.num_nodes() == layer.problem.num_nodes(), "skin map: subspace has {} nodes, the layer {}",
          subspace.num_nodes(), layer.problem.num_nodes());
  // K B column by column, three basis functions per call of the (linear) skin embedding; exact zeros dropped.
  const int S = subspace.num_functions();
  const Eigen::MatrixXd dense = Eigen::MatrixXd(subspace.basis);
  std::vector<Eigen::Triplet<double>> entries;
  for (int s = 0; s < S; s += 3) {
    meshing::RowMatrixX3d columns = meshing::RowMatrixX3d::Zero(subspace.num_nodes(), 3);
    const int count = std::min(3, S - s);
    columns.leftCols(count) = dense.middleCols(s, count);
    const meshing::RowMatrixX3d skin = layer.mesh->skin_positions(columns);
    for (Eigen::Index r = 0; r < skin.rows(); ++r)
      for (int k = 0; k < count; ++k)
        if (skin(r, k) != 0.0) entries.emplace_back(static_cast<int>(r), s + k, skin(r, k));
  }
  skin_basis_.resize(layer.mesh->region_surface.num_vertices(), S);
  skin_basis_.setFromTriplets(entries.begin(), entries.end());
}

meshing::RowMatrixX3d SkinDisplacementMap::displacement(const Eigen::VectorXd& q, double t) const {
  const model::Problem& p = layer_.problem;
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  p.apply_dirichlet(t, x);
  subspace_.add_displacement(q, x);
  return layer_.surface_displacement(x);
}

meshing::RowMatrixX3d SkinDisplacementMap::displacement_of(const Eigen::VectorXd& q) const {
  const Eigen::MatrixXd u = derivative(q);  // linear: the same map applied to one column
  return Eigen::Map<const meshing::RowMatrixX3d>(u.data(), skin_basis_.rows(), 3);
}

Eigen::MatrixXd SkinDisplacementMap::derivative(const Eigen::MatrixXd& dq) const {
  require(dq.rows() == subspace_.num_dofs(), "skin map: dq has {} rows, expected {}", dq.rows(), subspace_.num_dofs());
  const Eigen::Index R = skin_basis_.rows();
  Eigen::MatrixXd du = Eigen::MatrixXd::Zero(3 * R, dq.cols());
  for (Eigen::Index r = 0; r < R; ++r)
    for (SparseRowMatrix::InnerIterator it(skin_basis_, r); it; ++it)
      du.middleRows<3>(3 * r) += it.value() * dq.middleRows<3>(3 * it.col());
  return du;
}

}  // namespace sflsh::reduced
