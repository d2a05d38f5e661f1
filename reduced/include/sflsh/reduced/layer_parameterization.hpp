#pragma once
// The material of a layer as a function of its N control-point values κ_i (SFLSH §3): the control points
// and their biharmonic basis φ on the template region, computed once per N, and the fast path that turns
// κ (N × 3, physical) into a subject's problem — thickness field → retargeted nodes → κ per tet → tet
// materials and lumped masses — without rebuilding anything that does not depend on κ (the template mesh,
// the skinning trajectory, the reduced model). A fit evaluates it hundreds of times per iteration.
#include <sflsh/material/parameters.hpp>
#include <sflsh/meshing/retarget.hpp>
#include <sflsh/model/body_layer.hpp>

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace sflsh::reduced {

class LayerParameterization {
 public:
  /// `base` fixes the body model and template mesh (any subject of that template works afterwards).
  /// `control_points` ≥ 1: the first N of the nested control-point sequence (material/control_points.hpp).
  LayerParameterization(const model::BodyLayer& base, int control_points);

  int num_controls() const { return static_cast<int>(control_vertices_.size()); }
  const std::vector<int>& control_vertices() const { return control_vertices_; }  ///< body vertex indices
  const Eigen::MatrixXd& phi() const { return phi_; }                             ///< R × N
  /// The region index of each control point (row of φ where φ_i = 1).
  const std::vector<int>& control_region_vertices() const { return control_local_; }
  const meshing::LayerMesh& mesh() const { return *mesh_; }
  const meshing::Retargeter& retargeter() const { return *retargeter_; }

  /// `layer`'s problem with the material κ (N × 3, physical, validated against `bounds`): a copy of the
  /// layer's problem with new rest nodes, tet materials and masses; `rest_skin` receives the region skin
  /// at rest (R × 3). Thread-safe (const). Throws when κ is out of range or the retarget inverts a tet.
  /// With `shaped` (retargeter().shape(layer.beta), made once per subject) the retarget skips its β part and checks
  /// the mesh by the light pass (meshing::RetargetCheck::light): the same problem, bit for bit, and the same
  /// errors, for a fraction of the set-up.
  /// `untangled_nodes`, when given, receives RetargetedLayer::untangled_nodes (nodes are affine in h only at 0).
  model::Problem problem(const model::BodyLayer& layer, const material::KappaMatrix& kappa,
                         const model::BodyLayerOptions& options, meshing::RowMatrixX3d* rest_skin = nullptr,
                         const meshing::ShapedLayer* shaped = nullptr, int* untangled_nodes = nullptr) const;

  /// The same for κ given at every region vertex (R × 3, physical): any field, not only the span of φ.
  model::Problem problem_from_field(const model::BodyLayer& layer, const material::KappaMatrix& kappa_vertex,
                                    const model::BodyLayerOptions& options, meshing::RowMatrixX3d* rest_skin = nullptr,
                                    const meshing::ShapedLayer* shaped = nullptr, int* untangled_nodes = nullptr) const;

  /// κ per region vertex (R × 3) for control values κ (N × 3): φ κ.
  material::KappaMatrix field(const material::KappaMatrix& kappa) const;

 private:
  const body::BodyModel* model_ = nullptr;
  std::shared_ptr<const meshing::LayerMesh> mesh_;
  std::unique_ptr<meshing::Retargeter> retargeter_;
  std::vector<int> control_vertices_, control_local_;
  Eigen::MatrixXd phi_;
  double poisson_ = 0.2, saturation_ = 4.0;
  material::ParameterBounds bounds_;
};

/// Values at the control points of `to` of the field given by control values `values` (N_from × k) of
/// `from` (φ_from evaluated at the new control vertices): the warm start of a progressive fit.
Eigen::MatrixXd transfer_control_values(const LayerParameterization& from, const LayerParameterization& to,
                                        const Eigen::MatrixXd& values);

}  // namespace sflsh::reduced
