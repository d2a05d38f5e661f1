#pragma once
// The open body's joint regressor, fitted over the population.
#include "body_field.hpp"
#include "skeleton.hpp"

#include <sflsh/body/body_model.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

namespace sflsh::body::detail {

using JointArray = std::array<Eigen::Vector3d, kNumJoints>;

/// Fits 𝒥 (24×n) so that 𝒥 V_k reproduces every sample's skeleton joints.
///
/// Each joint j is a convex combination (w ≥ 0, Σw = 1) of the template vertices around it in every
/// direction (where rays from the joint leave the body, up to max(2.5 d, d + 5 cm) away, d the
/// distance to the nearest vertex). The weights minimise
///   (1/N) Σ_k ‖Σ_i w_i (V_k,i − J̄) − (J_k − J̄)‖² + λ ‖w − 1/K‖²
/// (J̄ the template joint, λ a small ridge towards the uniform ring) by accelerated projected gradient
/// on the simplex; a convex combination of a ring of surface points stays inside the body.
/// Right joints use the mirror images of their left partners' vertices and central joints are
/// symmetrised, so the regressor is exactly left/right symmetric.
///
/// @param[in] template_vertices  n×3 template surface [m] (on `template_field`'s f = 0)
/// @param[in] mirror             index of each vertex's mirror image (x → −x)
/// @param[in] sample_vertices    3n×N population surfaces, column k = V_k flattened (row 3v + c)
/// @param[in] sample_joints      N joint sets of the population's skeletons [m]
Eigen::SparseMatrix<double, Eigen::RowMajor> fit_joint_regressor(const RowMatrixX3d& template_vertices,
                                                                 const std::vector<int>& mirror,
                                                                 const BodyField& template_field,
                                                                 const Skeleton& template_skeleton,
                                                                 const Eigen::MatrixXd& sample_vertices,
                                                                 const std::vector<JointArray>& sample_joints);

}  // namespace sflsh::body::detail
