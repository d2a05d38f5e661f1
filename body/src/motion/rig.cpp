#include "rig.hpp"

#include "curves.hpp"

#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace sflsh::body::motion_detail {

Eigen::Quaterniond rot_x(double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()));
}
Eigen::Quaterniond rot_y(double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()));
}
Eigen::Quaterniond rot_z(double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
}

Eigen::Vector3d log_rotation(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // canonical half: angle ∈ [0, π]
  const double s = q.vec().norm();            // sin(angle/2)
  if (s == 0.0) return Eigen::Vector3d::Zero();
  // angle = 2 atan2(s, w); atan2 keeps full relative precision for small s.
  return (2.0 * std::atan2(s, q.w()) / s) * q.vec();
}

Eigen::Quaterniond exp_rotation(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  if (angle == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle));
}

Eigen::Quaterniond fraction(const Eigen::Quaterniond& q, double s) { return exp_rotation(s * log_rotation(q)); }

void set_joint(Pose& theta, int joint, const Eigen::Quaterniond& local) {
  theta.segment<3>(3 * joint) = log_rotation(local);
}

Eigen::Quaterniond joint_rotation(const Pose& theta, int joint) { return exp_rotation(theta.segment<3>(3 * joint)); }

namespace {
int hip_of(Side s) { return s == Side::kLeft ? kLeftHip : kRightHip; }
int knee_of(Side s) { return s == Side::kLeft ? kLeftKnee : kRightKnee; }
int ankle_of(Side s) { return s == Side::kLeft ? kLeftAnkle : kRightAnkle; }
int foot_of(Side s) { return s == Side::kLeft ? kLeftFoot : kRightFoot; }
}  // namespace

void set_leg(Pose& theta, Side side, const LegAngles& leg) {
  const double s = sign(side);
  set_joint(theta, hip_of(side), rot_z(s * leg.hip_abduction) * rot_x(-leg.hip_flexion));
  set_joint(theta, knee_of(side), rot_x(leg.knee_flexion));
  set_joint(theta, ankle_of(side), rot_x(leg.ankle_plantar_flexion) * rot_z(-s * leg.hip_abduction));
  set_joint(theta, foot_of(side), rot_x(-leg.toe_extension));
}

void set_arm(Pose& theta, Side side, const ArmAngles& arm) {
  const double s = sign(side);
  const int collar = side == Side::kLeft ? kLeftCollar : kRightCollar;
  const int shoulder = side == Side::kLeft ? kLeftShoulder : kRightShoulder;
  const int elbow = side == Side::kLeft ? kLeftElbow : kRightElbow;
  const Eigen::Quaterniond girdle = rot_y(-s * arm.protraction);
  const Eigen::Quaterniond collar_local = girdle * rot_z(-s * arm.collar_share * arm.down);
  const Eigen::Quaterniond upper_arm = girdle * rot_x(-arm.swing) * rot_z(-s * arm.down);  // relative to the chest
  set_joint(theta, collar, collar_local);
  set_joint(theta, shoulder, collar_local.conjugate() * upper_arm);
  set_joint(theta, elbow, rot_y(-s * arm.elbow_flexion));
}

void set_arms_in_opposition(Pose& theta, ArmAngles arm, double swing, double elbow_swing) {
  const double base_swing = arm.swing, base_elbow = arm.elbow_flexion;
  arm.swing = base_swing + swing;
  arm.elbow_flexion = base_elbow + elbow_swing;
  set_arm(theta, Side::kLeft, arm);
  arm.swing = base_swing - swing;
  arm.elbow_flexion = base_elbow - elbow_swing;
  set_arm(theta, Side::kRight, arm);
}

Eigen::Vector3d nominal_rest_ankle(Side side) {
  return {sign(side) * NominalLeg::hip_offset_x, NominalLeg::hip_offset_y - NominalLeg::thigh - NominalLeg::shank, 0.0};
}

void plant_feet(Pose& theta, const Eigen::Quaterniond& pelvis, const Eigen::Vector3d& pelvis_world) {
  for (const Side side : {Side::kLeft, Side::kRight}) {
    const LegIkResult leg = solve_leg_ik(side, pelvis, pelvis_world, nominal_rest_ankle(side),
                                         Eigen::Quaterniond::Identity(), Eigen::Vector3d::UnitZ());
    const bool left = side == Side::kLeft;
    set_joint(theta, left ? kLeftHip : kRightHip, leg.hip);
    set_joint(theta, left ? kLeftKnee : kRightKnee, rot_x(leg.knee_flexion));
    set_joint(theta, left ? kLeftAnkle : kRightAnkle, leg.ankle);
  }
}

LegIkResult solve_leg_ik(Side side, const Eigen::Quaterniond& pelvis, const Eigen::Vector3d& pelvis_world,
                         const Eigen::Vector3d& ankle_world, const Eigen::Quaterniond& foot_world,
                         const Eigen::Vector3d& pole) {
  const double l1 = NominalLeg::thigh, l2 = NominalLeg::shank;
  const Eigen::Vector3d hip_offset(sign(side) * NominalLeg::hip_offset_x, NominalLeg::hip_offset_y, 0.0);
  const Eigen::Vector3d hip = pelvis_world + pelvis * hip_offset;
  const Eigen::Vector3d d = ankle_world - hip;
  const double D = d.norm();
  const double reach = std::sqrt(l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * std::cos(deg(2.0)));
  require(D <= reach && D >= std::abs(l1 - l2) + 1e-6,
          "leg IK: ankle at {:.4f} m from the hip, reachable range is up to {:.4f} m (knee ≥ 2°)", D, reach);
  // Law of cosines: D² = l1² + l2² + 2 l1 l2 cos κ (κ = 0 straight); thigh at α from the hip–ankle line.
  LegIkResult out;
  out.knee_flexion = std::acos(std::clamp((D * D - l1 * l1 - l2 * l2) / (2.0 * l1 * l2), -1.0, 1.0));
  const double alpha = std::acos(std::clamp((l1 * l1 + D * D - l2 * l2) / (2.0 * l1 * D), -1.0, 1.0));
  const Eigen::Vector3d dn = d / D;
  const Eigen::Vector3d pole_perp = (pole - pole.dot(dn) * dn).normalized();
  const Eigen::Vector3d u = std::cos(alpha) * dn + std::sin(alpha) * pole_perp;  // thigh direction
  // Thigh frame: local −Y along the thigh, local +Z forward in the leg plane, X = Y × Z (knee axis).
  Eigen::Matrix3d frame;
  frame.col(1) = -u;
  frame.col(2) = (pole - pole.dot(u) * u).normalized();
  frame.col(0) = frame.col(1).cross(frame.col(2));
  const Eigen::Quaterniond thigh(frame);
  out.hip = pelvis.conjugate() * thigh;
  const Eigen::Quaterniond shank = thigh * rot_x(out.knee_flexion);
  out.ankle = shank.conjugate() * foot_world;
  return out;
}

double leg_drop(double knee_flexion) { return 2.0 * NominalLeg::thigh * (1.0 - std::cos(0.5 * knee_flexion)); }

double knee_for_drop(double drop) {
  assert(drop >= 0.0 && drop < 2.0 * NominalLeg::thigh);
  return 2.0 * std::acos(1.0 - drop / (2.0 * NominalLeg::thigh));
}

namespace {
double leg_tilt(double knee_flexion, double pitch) {
  const double l_eff = 2.0 * NominalLeg::thigh * std::cos(0.5 * knee_flexion);
  return std::asin(toe_forward_shift(pitch) / l_eff);
}
}  // namespace

LegAngles planted_leg(double knee_flexion, double pitch) {
  const double beta = leg_tilt(knee_flexion, pitch);
  LegAngles leg;
  leg.hip_flexion = 0.5 * knee_flexion + beta;
  leg.knee_flexion = knee_flexion;
  leg.ankle_plantar_flexion = pitch - 0.5 * knee_flexion + beta;  // cumulative: −hip + knee + ankle = p
  leg.toe_extension = pitch;
  return leg;
}

double planted_leg_height(double knee_flexion, double pitch) {
  const double l_eff = 2.0 * NominalLeg::thigh * std::cos(0.5 * knee_flexion);
  const double shift = toe_forward_shift(pitch);
  return toe_rise(pitch) + std::sqrt(l_eff * l_eff - shift * shift) - 2.0 * NominalLeg::thigh;
}

double toe_rise(double pitch) {
  return NominalLeg::ankle_to_ball * std::sin(pitch) + NominalLeg::ankle_height * (std::cos(pitch) - 1.0);
}

double toe_forward_shift(double pitch) {
  return NominalLeg::ankle_to_ball * (1.0 - std::cos(pitch)) + NominalLeg::ankle_height * std::sin(pitch);
}

}  // namespace sflsh::body::motion_detail
