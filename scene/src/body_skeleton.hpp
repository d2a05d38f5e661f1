#pragma once
// A scene body's tracking skeleton (docs/scenes.md "Skeletons that answer contact"): the reduced solver's joint
// options from the body's keys (tracked joints, springs, dampers, limits; the skinning weights of the layer's nodes
// and the posed joint centres along the motion), and the deviation's per-vertex maps of the body surface.
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <string>
#include <vector>

namespace sflsh::scene::detail {

/// The joints below the root that carry part of the layer (a node weighted on the joint or below it), ascending.
std::vector<int> joints_carrying_the_layer(const model::BodyLayer& layer);

/// The reduced solver's joint options for `spec` (tracked_joints "root" or a list without carrying joints: none).
reduced::JointTrackingOptions joint_tracking_options(const BodySpec& spec, const model::BodyLayer& layer);

/// Per body vertex the deviation's affine map [L | y(0)] in the body's posed frame (one per row of the surface).
std::vector<reduced::Matrix34d> surface_deviation_maps(const reduced::ReducedSolver& solver,
                                                       const model::BodyLayer& layer);
/// Per layer node the same.
std::vector<reduced::Matrix34d> node_deviation_maps(const reduced::ReducedSolver& solver,
                                                    const model::BodyLayer& layer);
/// Points deviated by per-row maps.
meshing::RowMatrixX3d apply_maps(const std::vector<reduced::Matrix34d>& maps, const meshing::RowMatrixX3d& points);

}  // namespace sflsh::scene::detail
