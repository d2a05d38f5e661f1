#pragma once
// The anthropometric skeleton of one open-body sample: SMPL's 24 joints and the body dimensions
// (trunk sections, limb radii) derived from its anthropometric factors.
//
// Frame: metres, Y up, the body faces +Z, its left side is +X; the pelvis joint is at the origin.
// Proportions follow Drillis & Contini (fractions of stature H, average H = 1.70 m).
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/open_body.hpp>

#include <Eigen/Core>

#include <array>
#include <vector>

namespace sflsh::body::detail {

/// Multiplicative scales of one sample (1 at the average body).
struct BodyScales {
  double stature = 1.70;  ///< H [m]
  double legs = 1.0;      ///< vertical scale of the legs (keeps H when the trunk grows)
  double trunk = 1.0;     ///< vertical scale of the trunk (torso_length)
  double frame = 1.0;     ///< lateral scale of the skeleton
  double girth = 1.0;     ///< radial scale of the soft tissue
  double shoulders = 1.0, hips = 1.0, chest = 1.0, breasts = 1.0, belly = 1.0, buttocks = 1.0;
  double thighs = 1.0, arms = 1.0;
  double extremities = 1.0;  ///< head, hands and feet
};

/// One elliptic cross-section of the trunk: x²/a² + (z − c)²/b² = 1 at height y [m].
struct TrunkSection {
  double y, a, b, c;
};

struct Skeleton {
  BodyScales scales;
  std::array<Eigen::Vector3d, kNumJoints> joints;            ///< SMPL joint positions [m]
  double floor_y = 0.0;                                      ///< height of the soles [m]
  double head_top_y = 0.0;                                   ///< height of the vertex of the head [m]
  Eigen::Vector3d arm_direction = Eigen::Vector3d::UnitX();  ///< left arm, shoulder → hand (unit)
  std::vector<TrunkSection> trunk;                           ///< torso loft knots, bottom to top
  // Limb radii [m].
  double thigh_top = 0, thigh_knee = 0, shank_knee = 0, shank_ankle = 0;
  double upper_arm_top = 0, upper_arm_elbow = 0, forearm_elbow = 0, forearm_wrist = 0;
  double neck_base = 0, neck_top = 0;

  /// World height [m] of a fraction of stature measured from the floor (Drillis & Contini levels).
  double level(double fraction) const;
  /// Linear interpolation of the trunk sections at height y [m] (clamped to the ends).
  TrunkSection trunk_at(double y) const;
  /// Lengths that scale with stature (hands, feet, head) [m] for a length given at H = 1.70 m.
  double extremity(double length_at_average) const { return scales.extremities * length_at_average; }

  double pelvis_height = 0.0;  ///< floor-to-pelvis-joint height before the origin shift [m]
};

/// Lateral (x) squash of the thigh cross-section: thighs are deeper than wide, which keeps the crotch open.
inline constexpr double kThighSquash = 0.85;

/// The skeleton and dimensions of the body with factors z (z = 0: the average body).
Skeleton make_skeleton(const AnthroFactors& z);

/// Left joint index → right joint index (and the reverse); central joints map to themselves.
int mirror_joint(int joint);

}  // namespace sflsh::body::detail
