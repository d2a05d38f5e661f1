#pragma once
// Template-to-sample correspondence: the template surface carried onto another sample's surface,
// vertex for vertex, so that the population can be compared by PCA.
#include "body_field.hpp"
#include "mesh_topology.hpp"
#include "skeleton.hpp"

#include <sflsh/body/body_model.hpp>

#include <Eigen/Core>

namespace sflsh::body::detail {

/// An affine bone frame: origin (the joint) [m], orthonormal axes (columns; the first along the bone)
/// and the bone's characteristic extents along them [m] (length, and two girths).
struct BoneFrame {
  Eigen::Vector3d origin;
  Eigen::Matrix3d axes;
  Eigen::Vector3d extents;
};

/// The 24 bone frames of a skeleton.
std::array<BoneFrame, kNumJoints> bone_frames(const Skeleton& skeleton);

/// The template vertices (n×3, on the template's f = 0) mapped onto the sample:
///  1. warp: x' = Σ_k w_k A_k x, with A_k the affine map taking bone k's template frame to its sample
///     frame (origin to origin, extents scaled per axis);
///  2. Newton projection of x' onto the sample's f = 0 along ∇f;
///  3. a few Jacobi steps of tangential relaxation towards the warped template's uniform-Laplacian
///     coordinates (over `adjacency`), each followed by projection, which keeps creases unfolded.
RowMatrixX3d carry_template(const RowMatrixX3d& template_vertices, const Eigen::MatrixXd& weights,
                            const VertexAdjacency& adjacency, const Skeleton& template_skeleton,
                            const Skeleton& sample_skeleton, const BodyField& sample_field);

}  // namespace sflsh::body::detail
