#include <sflsh/core/error.hpp>
#include <sflsh/material/biharmonic_basis.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/reduced/layer_parameterization.hpp>

namespace sflsh::reduced {

LayerParameterization::LayerParameterization(const model::BodyLayer& base, int control_points)
    : model_(base.model),
      mesh_(std::make_shared<meshing::LayerMesh>(*base.mesh)),
      poisson_(base.material.poisson),
      saturation_(base.material.saturation),
      bounds_(base.material.bounds) {
  require(model_ != nullptr, "layer parameterization: the body layer has no body model");
  require(control_points >= 1, "layer parameterization: at least one control point, got {}", control_points);
  retargeter_ = std::make_unique<meshing::Retargeter>(*model_, *mesh_);
  control_vertices_ = material::layer_control_points(*model_, *mesh_, control_points);
  const material::BiharmonicBasis basis = material::layer_basis(*model_, *mesh_, control_vertices_);
  phi_ = basis.phi;
  for (int v : control_vertices_) control_local_.push_back(mesh_->region_surface.local_of[static_cast<std::size_t>(v)]);
}

material::KappaMatrix LayerParameterization::field(const material::KappaMatrix& kappa) const {
  return material::evaluate_field(phi_, kappa);
}

model::Problem LayerParameterization::problem(const model::BodyLayer& layer, const material::KappaMatrix& kappa,
                                              const model::BodyLayerOptions& options, meshing::RowMatrixX3d* rest_skin,
                                              const meshing::ShapedLayer* shaped, int* untangled_nodes) const {
  require(layer.mesh && layer.mesh->num_nodes() == mesh_->num_nodes() && layer.mesh->num_tets() == mesh_->num_tets(),
          "layer parameterization: the layer is not on the template mesh the parameterization was built for");
  require(kappa.rows() == num_controls(), "layer parameterization: {} control values for {} control points",
          kappa.rows(), num_controls());
  material::validate(kappa, bounds_, "layer parameterization: control point");
  return problem_from_field(layer, field(kappa), options, rest_skin, shaped, untangled_nodes);
}

model::Problem LayerParameterization::problem_from_field(
    const model::BodyLayer& layer, const material::KappaMatrix& kappa_vertex, const model::BodyLayerOptions& options,
    meshing::RowMatrixX3d* rest_skin, const meshing::ShapedLayer* shaped, int* untangled_nodes) const {
  require(layer.mesh && layer.mesh->num_nodes() == mesh_->num_nodes() && layer.mesh->num_tets() == mesh_->num_tets(),
          "layer parameterization: the layer is not on the template mesh the parameterization was built for");
  const Eigen::VectorXd thickness = kappa_vertex.col(material::kThickness);
  if (shaped)
    require(shaped->beta.size() == layer.beta.size() && shaped->beta == layer.beta,
            "layer parameterization: the shaped layer was prepared for another β");
  const meshing::RetargetedLayer retargeted =
      shaped ? retargeter_->retarget(*shaped, thickness, meshing::RetargetCheck::light)
             : retargeter_->retarget(layer.beta, thickness);
  if (untangled_nodes) *untangled_nodes = retargeted.untangled_nodes;
  const material::LayerMaterialFields fields =
      material::layer_material_fields(*retargeter_, kappa_vertex, retargeted.nodes);

  model::Problem p = layer.problem;  // tets, Dirichlet set and trajectory do not depend on κ
  p.rest = retargeted.nodes;
  p.tet_rest.clear();
  for (int e = 0; e < mesh_->num_tets(); ++e) {
    material::SkinMaterial m;
    m.young_tangent = options.stiffness_scale * fields.tet(e, material::kYoungTangent);
    m.young_normal = options.stiffness_scale * fields.tet(e, material::kYoungNormal);
    m.poisson = poisson_;
    m.saturation = saturation_;
    m.overflow = options.overflow;
    p.tet_material[static_cast<std::size_t>(e)] = material::make_orthotropic_fung(m, fields.normal.row(e).transpose());
  }
  p.mass = model::lumped_masses(p.rest, p.tets, p.density > 0.0 ? p.density : options.density);
  p.validate();
  if (rest_skin) *rest_skin = mesh_->skin_positions(p.rest);
  return p;
}

Eigen::MatrixXd transfer_control_values(const LayerParameterization& from, const LayerParameterization& to,
                                        const Eigen::MatrixXd& values) {
  require(values.rows() == from.num_controls(), "control transfer: {} values for {} control points", values.rows(),
          from.num_controls());
  Eigen::MatrixXd out(to.num_controls(), values.cols());
  for (int i = 0; i < to.num_controls(); ++i)
    out.row(i) = from.phi().row(to.control_region_vertices()[static_cast<std::size_t>(i)]) * values;
  return out;
}

}  // namespace sflsh::reduced
