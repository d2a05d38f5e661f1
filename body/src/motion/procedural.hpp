#pragma once
// The procedural DYNA-like motions as continuous functions of time (private to sflsh::body).
// Each is sampled by make_procedural_motion() at the requested frame rate.
#include <sflsh/body/skinning.hpp>

#include <span>
#include <string_view>

namespace sflsh::body::motion_detail {

/// Pose and root translation [m] at one instant.
struct PoseSample {
  Pose theta = Pose::Zero();
  Eigen::Vector3d trans = Eigen::Vector3d::Zero();
};

/// A procedural motion: θ(t), trans(t) defined for all t ≥ 0 [s], equal to the rest pose at t = 0.
struct ProceduralSpec {
  std::string_view name;
  std::string_view description;  ///< one line, for `sflsh motion list`
  double default_seconds;        ///< default length [s]
  PoseSample (*sample)(double t);
  /// Periodic motions only: the sample with the steady part shifted by `offset` [s] (ease-in kept at t).
  PoseSample (*sample_offset)(double t, double offset) = nullptr;
  double period = 0.0;  ///< [s] of the steady part; 0: not periodic by construction
};

/// The five motions in DYNA order (training: one_leg_jump, running_on_spot, shake_hips; testing:
/// jiggle_on_toes, shake_shoulders).
std::span<const ProceduralSpec> procedural_specs();
/// Showcase motions (not DYNA, not in procedural_motion_names()): dance.
std::span<const ProceduralSpec> showcase_specs();

/// Ease-in from the rest T-pose shared by all motions [s].
inline constexpr double kEaseInSeconds = 0.5;

/// Blends a steady-state sample toward the rest pose: every joint's axis-angle vector and the root
/// translation are scaled by `weight` ∈ [0, 1] (per joint, this is slerp from the identity).
PoseSample scaled_from_rest(const PoseSample& steady, double weight);

PoseSample sample_one_leg_jump(double t);          // procedural_jump.cpp
PoseSample sample_running_on_spot(double t);       // procedural_running.cpp
PoseSample sample_shake_hips(double t);            // procedural_shake.cpp
PoseSample sample_shake_shoulders(double t);       // procedural_shake.cpp
PoseSample sample_jiggle_on_toes(double t);        // procedural_toes.cpp
PoseSample sample_dance(double t, double offset);  // procedural_dance.cpp
double dance_period();                             // procedural_dance.cpp

}  // namespace sflsh::body::motion_detail
