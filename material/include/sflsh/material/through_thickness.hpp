#pragma once
// The through-thickness normal n per tet (docs/physics.md §1.3): the normalized gradient of a Laplace field
// that is 0 on the skin and 1 on the inner surface (the layer's depth coordinate), pointing outward
// (towards the skin). n is the axis of the transversely isotropic skin material.
#include <sflsh/meshing/types.hpp>

namespace sflsh::material {

/// n_e = −∇d / |∇d| on each linear tet, for node positions `nodes` and a nodal depth field `depth`
/// (Retargeter::depth_field()). Throws naming the tet when the gradient vanishes or is not finite.
meshing::RowMatrixX3d through_thickness_normals(const meshing::RowMatrixX3d& nodes, const meshing::RowMatrixX4i& tets,
                                                const Eigen::VectorXd& depth);

}  // namespace sflsh::material
