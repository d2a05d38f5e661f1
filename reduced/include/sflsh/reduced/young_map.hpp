#pragma once
// How the Young moduli of the material's control points reach the cubature tets and how the reduced
// coordinates reach the skin, as linear maps (SFLSH §3, layer_material.hpp, docs/physics.md §2.1):
//   Y_tet = W Y_control,  W = stiffness_scale · T · X · φ,
// with φ the region's biharmonic basis (R × N), X the retargeter's harmonic extension of a skin field to the
// nodes (linear for fixed geometry) and T the mean over a tet's four nodes; the same W serves Y_t and Y_n. The
// thickness h moves the rest geometry (retargeting) and is not part of this map.
#include <sflsh/meshing/retarget.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <vector>

namespace sflsh::reduced {

/// W for the listed tets (tets.size() × N): row k gives the modulus of tet tets[k] from the N control values. With a
/// LayerParameterization p (layer_parameterization.hpp): young_tet_map(p.retargeter(), p.phi(), tets, scale).
/// @param[in] retargeter       the layer's retargeter (its harmonic extension)
/// @param[in] phi              #region vertices by N basis
/// @param[in] tets             mesh tets (e.g. Cubature::tets)
/// @param[in] stiffness_scale  BodyLayerOptions::stiffness_scale (multiplies Y)
Eigen::MatrixXd young_tet_map(const meshing::Retargeter& retargeter, const Eigen::MatrixXd& phi,
                              const std::vector<int>& tets, double stiffness_scale = 1.0);

/// The material maps of one body layer: its basis and retargeter, rebuilt once (the layer keeps neither).
/// The layer and its body model must outlive the map.
class LayerYoungMap {
 public:
  /// @param[in] stiffness_scale  the BodyLayerOptions::stiffness_scale the layer was built with
  LayerYoungMap(const model::BodyLayer& layer, double stiffness_scale = 1.0);

  int num_controls() const { return static_cast<int>(phi_.cols()); }
  /// W for the listed tets (young_tet_map).
  Eigen::MatrixXd tet_map(const std::vector<int>& tets) const;
  /// The control moduli of the layer's material (N × 2: Y_t, Y_n) [Pa], before the stiffness scale.
  Eigen::MatrixX2d control_young() const;
  /// Rebuilds problem.tet_material (every tet) for control moduli `young` (N × 2) [Pa] through
  /// layer_material_fields, with thickness, normals, ν, s and the overflow policy as built. The problem
  /// must be the layer's (or a copy of it).
  void set_control_young(const Eigen::MatrixX2d& young, model::Problem& problem) const;
  const Eigen::MatrixXd& basis() const { return phi_; }
  const meshing::Retargeter& retargeter() const { return retargeter_; }

 private:
  const model::BodyLayer& layer_;
  double stiffness_scale_;
  Eigen::MatrixXd phi_;
  meshing::Retargeter retargeter_;
};

/// The region skin's unposed displacement as a map of the reduced coordinates. BodyLayer::surface_displacement
/// is linear in x and x = x_D + (B ⊗ I₃) q, so u = u(x_D) + (K B ⊗ I₃) q with K the skin embedding
/// (LayerMesh::skin_positions) and du/dp = (K B ⊗ I₃) dq/dp.
class SkinDisplacementMap {
 public:
  /// The layer and subspace must outlive the map.
  SkinDisplacementMap(const model::BodyLayer& layer, const Subspace& subspace);
  /// u (R × 3) [m] for coordinates q at time t [s].
  meshing::RowMatrixX3d displacement(const Eigen::VectorXd& q, double t) const;
  /// (K B ⊗ I₃) q (R × 3) [m]: the skin's displacement when the attached nodes carry none (x_D = X).
  meshing::RowMatrixX3d displacement_of(const Eigen::VectorXd& q) const;
  /// du/dp (3R × m, row 3r + axis) for dq/dp (3S × m).
  Eigen::MatrixXd derivative(const Eigen::MatrixXd& dq) const;
  /// K B (R × S): skin vertex r moves by Σ_s (K B)_rs q_s (q_s the three coordinates of function s).
  const SparseRowMatrix& skin_basis() const { return skin_basis_; }

 private:
  const model::BodyLayer& layer_;
  const Subspace& subspace_;
  SparseRowMatrix skin_basis_;  ///< K B (R × S), a few non-zeros per row
};

}  // namespace sflsh::reduced
