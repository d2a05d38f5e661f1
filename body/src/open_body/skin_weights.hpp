#pragma once
// Skinning weights of the open body's template surface.
#include "body_field.hpp"
#include "skeleton.hpp"

#include <Eigen/Core>

#include <vector>

namespace sflsh::body::detail {

/// Skinning weights (n×24, rows sum to 1, at most 4 nonzeros per row) of `vertices` (n×3 on f = 0):
///  1. each vertex's share of every primitive (∂f/∂d_i of the smooth-min chain) goes to the
///     primitive's bone; trunk primitives are split between pelvis/spine1/spine2/spine3 by height,
///     and towards the collars at the top of the chest and back;
///  2. Jacobi diffusion on the surface (uniform Laplacian) blends the bones across joints, each vertex
///     only receiving bones within two steps of its dominant bone in the kinematic tree and never
///     limbs of the other side beyond 2 cm of the mid-plane (no bleeding across the crotch, and
///     none from the arms into the chest);
///  3. exact left/right symmetry: w(v, k) and w(mirror(v), mirror(k)) are averaged;
///  4. truncation to the 4 largest weights (smaller than 0.01 dropped) and renormalisation.
/// `mirror` maps each vertex to its mirror image (x → −x).
Eigen::MatrixXd skinning_weights(const RowMatrixX3d& vertices, const RowMatrixX3i& faces,
                                 const std::vector<int>& mirror, const BodyField& field, const Skeleton& skeleton);

}  // namespace sflsh::body::detail
