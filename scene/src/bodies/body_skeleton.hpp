#pragma once
// A scene body's tracking skeleton (docs/scenes.md "Skeletons that answer contact"): the reduced solver's joint
// options from the body's keys (tracked joints, springs, dampers, limits; the skinning weights of the layer's nodes
// and the posed joint centres along the motion), and the deviation's per-vertex maps of the body surface.
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::scene::detail {

/// Per skeleton joint, the mass of the layer it carries [kg]: Σ_i m_i Σ_k w_ik over the joints k at or below it (the
/// root: the whole layer's mass).
std::vector<double> carried_mass(const model::BodyLayer& layer);

/// `tracked_joints = "all"` tracks the joints carrying at least this share of the layer's mass: a joint carrying less
/// (a knee or an elbow at the layer's edge, whose limb the layer does not hold) would swing on a few grams.
constexpr double kMinCarriedShare = 0.02;

/// The reduced solver's joint options for `spec` (tracked_joints "root", or nothing carried: none), logged once.
reduced::JointTrackingOptions joint_tracking_options(const BodySpec& spec, const model::BodyLayer& layer);

/// Per body vertex the deviation's affine map [L | y(0)] in the body's posed frame (one per row of the surface).
std::vector<reduced::Matrix34d> surface_deviation_maps(const reduced::ReducedSolver& solver,
                                                       const model::BodyLayer& layer);
/// Per layer node the same.
std::vector<reduced::Matrix34d> node_deviation_maps(const reduced::ReducedSolver& solver,
                                                    const model::BodyLayer& layer);
/// `<body>_skeleton.csv`: per step t_s, the root's rotation vector θ [rad] and translation τ [m] and each tracked
/// joint's rotation vector φ [rad] (the body's posed frame), one column per component, named by joint.
void write_deviation_csv(const std::filesystem::path& path, const reduced::SkeletonDeviation& skeleton,
                         const std::vector<std::pair<double, Eigen::VectorXd>>& history);
/// Points deviated by per-row maps.
meshing::RowMatrixX3d apply_maps(const std::vector<reduced::Matrix34d>& maps, const meshing::RowMatrixX3d& points);

}  // namespace sflsh::scene::detail
