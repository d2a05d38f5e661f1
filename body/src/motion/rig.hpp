#pragma once
// Posing helpers for the procedural motions (private to sflsh::body): SMPL joint indices, a nominal
// skeleton for the few kinematic constraints the motions keep (feet on the ground), rotation
// helpers, and setters that write anatomical angles into a pose vector θ.
//
// Conventions (SMPL; Y up, the body faces +Z, its left is +X). Joint k's rotation is expressed in its
// parent's frame, which in the rest T-pose is aligned with the world axes. With right-handed rotations:
//   hip flexion (thigh forward)         = rotation about −X      knee flexion (shank back) = about +X
//   ankle plantar flexion (toes down)   = about +X               toe extension (toes up)   = about −X
//   hip abduction: left about +Z, right about −Z
//   arm down from the T-pose: left about −Z, right about +Z
//   arm swing forward (arm hanging)     = about −X
//   elbow flexion (forearm forward, T-pose palms down): left about −Y, right about +Y
//   collar protraction (shoulder forward): left about −Y, right about +Y
//   pelvis/trunk: forward lean about +X, roll toward the body's right (left hip up) about +Z, yaw about +Y
#include <sflsh/body/skinning.hpp>

#include <Eigen/Geometry>

namespace sflsh::body::motion_detail {

/// SMPL joint indices (kJointNames order).
enum Joint : int {
  kPelvis = 0,
  kLeftHip,
  kRightHip,
  kSpine1,
  kLeftKnee,
  kRightKnee,
  kSpine2,
  kLeftAnkle,
  kRightAnkle,
  kSpine3,
  kLeftFoot,
  kRightFoot,
  kNeck,
  kLeftCollar,
  kRightCollar,
  kHead,
  kLeftShoulder,
  kRightShoulder,
  kLeftElbow,
  kRightElbow,
  kLeftWrist,
  kRightWrist,
  kLeftHand,
  kRightHand
};

enum class Side : int { kLeft = 1, kRight = -1 };
inline double sign(Side s) { return static_cast<double>(static_cast<int>(s)); }

/// Nominal leg dimensions [m] (Drillis & Contini fractions of a 1.70 m stature, docs/architecture.md §2), used
/// only to keep feet planted; a real body's proportions differ a little, so feet may slide by a few mm.
struct NominalLeg {
  static constexpr double thigh = 0.42;          ///< hip → knee
  static constexpr double shank = 0.42;          ///< knee → ankle
  static constexpr double ankle_height = 0.07;   ///< ankle above the ground
  static constexpr double ankle_to_ball = 0.14;  ///< horizontal ankle → ball of the foot
  static constexpr double hip_offset_x = 0.085;  ///< |x| of a hip joint from the pelvis joint
  static constexpr double hip_offset_y = -0.09;  ///< y of the hip joints relative to the pelvis joint
};

/// Nominal lumbar/thoracic spine offsets [m] (parent joint → joint, rest pose): pelvis → spine1,
/// spine1 → spine2, spine2 → spine3. Used to keep the head in place while the pelvis moves.
struct NominalSpine {
  static Eigen::Vector3d pelvis_to_spine1() { return {0.0, 0.11, -0.01}; }
  static Eigen::Vector3d spine1_to_spine2() { return {0.0, 0.13, 0.01}; }
  static Eigen::Vector3d spine2_to_spine3() { return {0.0, 0.06, 0.01}; }
};

Eigen::Quaterniond rot_x(double angle);
Eigen::Quaterniond rot_y(double angle);
Eigen::Quaterniond rot_z(double angle);

/// Axis-angle vector (angle ∈ [0, π]) of a rotation; exact near the identity.
Eigen::Vector3d log_rotation(const Eigen::Quaterniond& q);
/// Rotation of an axis-angle vector; exact near zero.
Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& omega);
/// q^s on the shortest arc (s ∈ [0, 1] gives the part of q's rotation), via exp(s log q).
Eigen::Quaterniond fraction(const Eigen::Quaterniond& q, double s);

/// Writes joint k's local rotation into θ.
void set_joint(Pose& theta, int joint, const Eigen::Quaterniond& local);
Eigen::Quaterniond joint_rotation(const Pose& theta, int joint);

/// Anatomical leg angles [rad] (see the conventions above); ankle and toe angles are joint angles
/// (relative to the parent segment).
struct LegAngles {
  double hip_flexion = 0.0;
  double hip_abduction = 0.0;
  double knee_flexion = 0.0;
  double ankle_plantar_flexion = 0.0;
  double toe_extension = 0.0;
};
/// hip = R_z(±abduction) R_x(−flexion), knee = R_x(flexion), ankle = R_x(plantar flexion) R_z(∓abduction)
/// (the foot stays level when the thigh is abducted), toe = R_x(−extension).
void set_leg(Pose& theta, Side side, const LegAngles& leg);

/// Arm angles [rad], relative to the chest (spine3) frame.
struct ArmAngles {
  double down = 0.0;           ///< upper arm lowered from the T-pose (total of collar and shoulder)
  double collar_share = 0.15;  ///< part of `down` taken by the collar joint
  double protraction = 0.0;    ///< collar forward (+) / back (−) about the vertical; the arm follows it
  double swing = 0.0;          ///< upper arm forward (+) about the body's X axis
  double elbow_flexion = 0.0;
};
/// collar = R_y(∓protraction) R_z(∓share·down); the upper arm's orientation relative to the chest is
/// R_y(∓protraction) R_x(−swing) R_z(∓down) and the shoulder joint takes what the collar leaves;
/// elbow = R_y(∓flexion). Upper signs for the left arm.
void set_arm(Pose& theta, Side side, const ArmAngles& arm);
/// Both arms swinging in opposition: the left arm at `arm` with its swing and elbow flexion moved by +`swing` and
/// +`elbow_swing`, the right one by −`swing` and −`elbow_swing` [rad].
void set_arms_in_opposition(Pose& theta, ArmAngles arm, double swing, double elbow_swing);

/// Pose of a leg whose ankle is placed by two-bone inverse kinematics on the nominal leg.
struct LegIkResult {
  Eigen::Quaterniond hip;     ///< local rotation of the hip joint (in the pelvis frame)
  double knee_flexion = 0.0;  ///< [rad]
  Eigen::Quaterniond ankle;   ///< local rotation of the ankle joint (in the shank frame)
};
/// Places the ankle at `ankle_world` with the foot at orientation `foot_world` and the knee bending
/// toward `pole` (a world direction, e.g. +Z). The pelvis joint is at `pelvis_world` with global
/// rotation `pelvis`. Throws if the ankle is out of reach (leg straighter than 2°).
LegIkResult solve_leg_ik(Side side, const Eigen::Quaterniond& pelvis, const Eigen::Vector3d& pelvis_world,
                         const Eigen::Vector3d& ankle_world, const Eigen::Quaterniond& foot_world,
                         const Eigen::Vector3d& pole);

/// Rest position of an ankle relative to the pelvis joint on the nominal leg (straight legs).
Eigen::Vector3d nominal_rest_ankle(Side side);
/// Both feet planted flat at their rest places for a pelvis of global rotation `pelvis` at `pelvis_world`: the hips,
/// knees (bending toward +Z) and ankles by solve_leg_ik.
void plant_feet(Pose& theta, const Eigen::Quaterniond& pelvis, const Eigen::Vector3d& pelvis_world);
/// Hip-height drop [m] of a leg with hip flexion κ/2 and knee flexion κ (ankle under the hip):
/// 2 l (1 − cos(κ/2)) with l = thigh = shank.
double leg_drop(double knee_flexion);
/// Knee flexion κ with leg_drop(κ) = drop (drop ∈ [0, 2l)).
double knee_for_drop(double drop);
/// Ankle rise [m] when the foot pivots about the ball of the foot by plantar flexion p (heel up):
/// l_f sin p + h_a (cos p − 1); and its forward shift l_f (1 − cos p) + h_a sin p.
double toe_rise(double pitch);
double toe_forward_shift(double pitch);

/// Sagittal angles of a leg standing on the ball of its foot, which stays where it is in the rest
/// pose relative to the hip: knee flexion κ, foot pitch p (heel up). Pivoting about the ball moves
/// the ankle forward by toe_forward_shift(p), so the whole leg tilts forward by
/// β = asin(shift / L_eff), L_eff = 2l cos(κ/2): hip flexion κ/2 + β, ankle p − κ/2 + β, toes p (flat).
LegAngles planted_leg(double knee_flexion, double pitch);
/// Hip height change [m] of planted_leg(κ, p) relative to the rest pose (hip above the ball's rest place):
/// toe_rise(p) + √(L_eff² − shift²) − 2l.
double planted_leg_height(double knee_flexion, double pitch);

}  // namespace sflsh::body::motion_detail
