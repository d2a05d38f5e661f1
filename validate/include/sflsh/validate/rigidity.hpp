#pragma once
// How rigidly each body vertex follows its bones, for the pose fit (pose_fit.hpp, docs/validate.md "Rigidity
// weights"). Outside the soft region the body has no soft-tissue layer (head, forearms, hands, shanks, feet):
// those vertices move with the skeleton and get w = 1. Inside, the soft tissue between skin and bone is
// about as thick as the skin's distance D_i to the nearest bone, and a layer of thickness D under an inertial
// load deflects like ρ a D² / μ (a clamped slab), so the variance of its motion grows like D⁴. The fit weighs
// each residual by the inverse of that variance, relative to a reference depth D_0 below which the tissue
// counts as rigid:
//   w_i = 1 outside the soft region,   w_i = min(1, (D_0 / D_i)⁴) inside.
#include <sflsh/body/skinning.hpp>

#include <vector>

namespace sflsh::validate {

using body::RowMatrixX3d;

/// D_i: distance of each vertex of `shaped` to the nearest bone, the segment from a joint to its parent
/// (joints `joints` of the same shape) [m].
Eigen::VectorXd bone_distance(const body::BodyModel& model, const RowMatrixX3d& shaped,
                              const body::JointPositions& joints);

/// w_i per body vertex (see above) for the rest shape β = 0; `reference_depth` D_0 [m] > 0. Throws when a
/// soft vertex is out of range or D_0 is not positive.
Eigen::VectorXd rigidity_weights(const body::BodyModel& model, const std::vector<int>& soft_vertices,
                                 double reference_depth);

}  // namespace sflsh::validate
