#pragma once
// Smooth surface-to-skeleton correspondence c(s) of the layer's skin points (docs/physics.md §1.4).
// c is stored as an affine combination of joint positions, c(s) = Σ_j a_j(s) J_j with Σ_j a_j = 1,
// so it follows the skeleton of any shape β exactly: c(s, β) = Σ_j a_j(s) J_j(β).
#include <sflsh/body/skinning.hpp>
#include <sflsh/meshing/region.hpp>

#include <Eigen/SparseCore>

namespace sflsh::meshing {

struct SkeletonCorrespondence {
  Eigen::SparseMatrix<double, Eigen::RowMajor> joint_weights;  ///< R×24, rows sum to 1

  /// c(s) for every region vertex (R×3) given the joints of a shape.
  RowMatrixX3d points(const body::JointPositions& joints) const;
};

/// For each region vertex: the closest point on each bone of the region's joints (bone = joint to its
/// designated child, e.g. left_shoulder → left_elbow), blended by the vertex's skinning weights of those
/// joints, then smoothed over the surface (`smoothing_sweeps` Jacobi sweeps of the uniform Laplacian)
/// so that c has no jumps where bones meet. Throws when a vertex ends up closer than 2 mm to its c.
SkeletonCorrespondence skeleton_correspondence(const body::BodyModel& model, const Region& region,
                                               int smoothing_sweeps = 30);

/// The layer geometry of one shape: shaped skin s, correspondence c and thickness fraction h per
/// region vertex; positions of anchors follow p = Σ w_k [s_k + depth·h_k (c_k − s_k)].
struct LayerGeometry {
  RowMatrixX3d skin;          ///< s (R×3)
  RowMatrixX3d skeleton;      ///< c (R×3)
  Eigen::VectorXd thickness;  ///< h ∈ (0, 1) per region vertex

  Eigen::Vector3d position(const SurfaceAnchor& anchor) const;
  /// Maximum thickness |c − s| per region vertex [m].
  Eigen::VectorXd max_thickness() const;
};

/// The geometry for shape β and a thickness field (R values, each in (0, 1)); throws naming the first
/// offending vertex when h is outside (0, 1) or not finite.
LayerGeometry layer_geometry(const body::BodyModel& model, const Region& region,
                             const SkeletonCorrespondence& correspondence, const body::Betas& beta,
                             const Eigen::VectorXd& thickness);

/// Checks a thickness field: size R, finite, strictly inside (0, 1). `what` names it in the error.
void validate_thickness(const Eigen::VectorXd& thickness, int region_vertices, const std::string& what);

}  // namespace sflsh::meshing
