// Placement of the open body's primitives on a skeleton: the trunk loft with belly, breasts and
// buttocks, the shoulder girdle, neck and head, arms with mitten hands, legs with feet.
// All sizes are those of the average 1.70 m body [m], scaled by the sample's BodyScales.
#include "body_field.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace sflsh::body::detail {
namespace {

Eigen::Vector3d mirrored(const Eigen::Vector3d& p) { return {-p.x(), p.y(), p.z()}; }

RoundCone mirrored(RoundCone c) {
  c.a = mirrored(c.a);
  c.b = mirrored(c.b);
  c.squash_axis = mirrored(c.squash_axis);
  return c;
}

Ellipsoid mirrored(Ellipsoid e) {
  e.center = mirrored(e.center);
  for (int k = 0; k < 3; ++k) e.axes.col(k) = mirrored(Eigen::Vector3d(e.axes.col(k)));
  return e;
}

/// z of the front (sign +1) or back (sign −1) of the trunk section at height y and lateral offset x.
double trunk_surface_z(const Skeleton& sk, double x, double y, double sign) {
  const TrunkSection s = sk.trunk_at(y);
  const double t = std::min(std::abs(x) / s.a, 0.95);
  return s.c + sign * s.b * std::sqrt(1.0 - t * t);
}

class Builder {
 public:
  void add(const Primitive& shape, double blend, int bone) { out_.push_back({shape, blend, bone, false}); }
  /// Adds a left-side primitive and its mirror image on the right, joined to the union as one step.
  void add_pair(const RoundCone& left, double blend, int left_bone) {
    add_pair(Primitive::round_cone(left), Primitive::round_cone(mirrored(left)), blend, left_bone);
  }
  void add_pair(const Ellipsoid& left, double blend, int left_bone) {
    add_pair(Primitive::ellipsoid(left), Primitive::ellipsoid(mirrored(left)), blend, left_bone);
  }
  std::vector<PlacedPrimitive> take() { return std::move(out_); }

 private:
  void add_pair(const Primitive& left, const Primitive& right, double blend, int left_bone) {
    out_.push_back({left, blend, left_bone, true});
    out_.push_back({right, blend, left_bone < 0 ? left_bone : mirror_joint(left_bone), false});
  }

  std::vector<PlacedPrimitive> out_;
};

void add_trunk(const Skeleton& sk, Builder& out) {
  const BodyScales& s = sk.scales;
  TorsoLoft loft;
  for (const TrunkSection& section : sk.trunk) {
    loft.y.push_back(section.y);
    loft.a.push_back(section.a);
    loft.b.push_back(section.b);
    loft.c.push_back(section.c);
  }
  loft.cap_blend = 0.03;
  out.add(Primitive::torso_loft(loft), 0.0, kTrunkBone);

  // Belly: its centre stays 5 cm (× girth) behind the front of the waist, so it protrudes with size.
  const double belly_y = sk.level(0.59);
  Ellipsoid belly;
  belly.radii = Eigen::Vector3d(0.115, 0.100, 0.070) * s.girth * s.belly;
  belly.center = {0.0, belly_y, trunk_surface_z(sk, 0.0, belly_y, 1.0) - 0.05 * s.girth};
  out.add(Primitive::ellipsoid(belly), 0.06, kTrunkBone);

  // Breasts: 2.2 cm (× girth) behind the chest front.
  const double breast_y = sk.level(0.715);
  const double breast_x = 0.085 * s.frame * (1.0 + 0.5 * (s.shoulders - 1.0)) * std::sqrt(s.girth);
  Ellipsoid breast;
  breast.radii = Eigen::Vector3d(0.058, 0.052, 0.045) * s.girth * s.breasts;
  breast.center = {breast_x, breast_y, trunk_surface_z(sk, breast_x, breast_y, 1.0) - 0.022 * s.girth};
  out.add_pair(breast, 0.035, kTrunkBone);

  // Buttocks: 3.4 cm (× girth) in front of the back of the hips.
  const double buttock_y = sk.level(0.51);
  const double buttock_x = 0.068 * s.girth * s.hips;
  Ellipsoid buttock;
  buttock.radii = Eigen::Vector3d(0.085, 0.095, 0.062) * s.girth * s.buttocks;
  buttock.center = {buttock_x, buttock_y, trunk_surface_z(sk, buttock_x, buttock_y, -1.0) + 0.034 * s.girth};
  out.add_pair(buttock, 0.04, kTrunkBone);
}

void add_shoulders_neck_head(const Skeleton& sk, Builder& out) {
  const BodyScales& s = sk.scales;
  const auto& j = sk.joints;
  // Trapezius: from the side of the neck to the acromion, flattened vertically.
  RoundCone trapezius;
  trapezius.a = {0.035 * s.girth, sk.level(0.834), -0.030};
  trapezius.b = {j[16].x() - 0.03, sk.level(0.812), -0.022};
  trapezius.ra = 0.042 * s.girth;
  trapezius.rb = 0.040 * s.girth;
  trapezius.squash_axis = Eigen::Vector3d::UnitY();
  trapezius.squash = 0.7;
  out.add_pair(trapezius, 0.05, 13);

  // Deltoid: elongated along the upper arm, centred just lateral of the shoulder joint.
  const Eigen::Vector3d d = sk.arm_direction;
  Ellipsoid deltoid;
  deltoid.center = j[16] + 0.02 * d + Eigen::Vector3d(0.0, 0.006, 0.0);
  deltoid.axes.col(0) = d;
  deltoid.axes.col(1) = Eigen::Vector3d::UnitZ().cross(d);
  deltoid.axes.col(2) = Eigen::Vector3d::UnitZ();
  deltoid.radii = Eigen::Vector3d(0.075, 0.050, 0.052) * s.girth * (1.0 + 0.5 * (s.arms - 1.0));
  out.add_pair(deltoid, 0.045, 16);

  RoundCone neck;
  neck.a = {0.0, sk.level(0.815), -0.022};
  neck.b = {0.0, sk.level(0.895), -0.008};
  neck.ra = sk.neck_base;
  neck.rb = sk.neck_top;
  out.add(Primitive::round_cone(neck), 0.045, 12);

  const double hs = 1.0 + 0.5 * (s.extremities - 1.0);
  // Cranium, face with jaw, nose: head height (vertex to chin) ≈ 0.13 H.
  Ellipsoid skull;
  skull.radii = Eigen::Vector3d(0.078, 0.090, 0.098) * hs;
  skull.center = {0.0, sk.head_top_y - skull.radii.y(), 0.0};
  out.add(Primitive::ellipsoid(skull), 0.03, 15);

  Ellipsoid face;
  face.radii = Eigen::Vector3d(0.057, 0.066, 0.070) * hs;
  face.center = skull.center + Eigen::Vector3d(0.0, -0.058, 0.030) * hs;
  out.add(Primitive::ellipsoid(face), 0.035, 15);

  Ellipsoid nose;
  nose.radii = Eigen::Vector3d(0.013, 0.021, 0.017) * hs;
  nose.center = skull.center + Eigen::Vector3d(0.0, -0.040, 0.097) * hs;
  out.add(Primitive::ellipsoid(nose), 0.01, 15);
}

void add_arm(const Skeleton& sk, Builder& out) {
  const auto& j = sk.joints;
  const double e = sk.scales.extremities;
  const Eigen::Vector3d d = sk.arm_direction;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d up = z.cross(d);  // back of the hand (palms face down)

  RoundCone upper{j[16], j[18], sk.upper_arm_top, sk.upper_arm_elbow};
  out.add_pair(upper, 0.045, 16);
  RoundCone fore{j[18], j[20], sk.forearm_elbow, sk.forearm_wrist};
  out.add_pair(fore, 0.02, 18);

  Ellipsoid palm;
  palm.center = j[20] + 0.048 * e * d;
  palm.axes.col(0) = d;
  palm.axes.col(1) = up;
  palm.axes.col(2) = z;
  palm.radii = Eigen::Vector3d(0.052, 0.017, 0.041) * e;
  out.add_pair(palm, 0.02, 20);

  RoundCone fingers{j[20] + 0.085 * e * d, j[20] + 0.160 * e * d, 0.040 * e, 0.031 * e, up, 0.42};
  out.add_pair(fingers, 0.015, 22);

  RoundCone thumb{j[20] + e * (0.020 * d + 0.028 * z - 0.004 * up), j[20] + e * (0.068 * d + 0.060 * z - 0.010 * up),
                  0.016 * e, 0.013 * e};
  out.add_pair(thumb, 0.02, 20);
}

void add_leg(const Skeleton& sk, Builder& out) {
  const auto& j = sk.joints;
  const BodyScales& s = sk.scales;
  const double e = s.extremities;
  RoundCone thigh{j[1], j[4], sk.thigh_top, sk.thigh_knee, Eigen::Vector3d::UnitX(), kThighSquash};
  out.add_pair(thigh, 0.045, 1);
  RoundCone shank{j[4], j[7], sk.shank_knee, sk.shank_ankle};
  out.add_pair(shank, 0.02, 4);

  Ellipsoid calf;
  calf.center = j[4] + 0.28 * (j[7] - j[4]) + Eigen::Vector3d(0.0, 0.0, -0.02 * s.girth);
  calf.radii = Eigen::Vector3d(0.050, 0.095, 0.054) * s.girth * (1.0 + 0.5 * (s.thighs - 1.0));
  out.add_pair(calf, 0.03, 4);

  const Eigen::Vector3d& ankle = j[7];
  const double floor = sk.floor_y;
  RoundCone foot{{ankle.x(), floor + 0.028 * e, ankle.z() - 0.020 * e},
                 {ankle.x() + 0.008 * e, floor + 0.026 * e, ankle.z() + 0.120 * e},
                 0.034 * e,
                 0.044 * e,
                 Eigen::Vector3d::UnitY(),
                 0.6};
  out.add_pair(foot, 0.02, 7);
  Ellipsoid heel;
  heel.center = {ankle.x(), floor + 0.033 * e, ankle.z() - 0.036 * e};
  heel.radii = Eigen::Vector3d(0.030, 0.033, 0.032) * e;
  out.add_pair(heel, 0.02, 7);
  RoundCone instep{
      ankle, {ankle.x() + 0.006 * e, floor + 0.035 * e, ankle.z() + 0.095 * e}, 0.95 * sk.shank_ankle, 0.026 * e};
  out.add_pair(instep, 0.02, 7);
  RoundCone toes{j[10],
                 {ankle.x() + 0.012 * e, floor + 0.020 * e, ankle.z() + 0.165 * e},
                 0.042 * e,
                 0.030 * e,
                 Eigen::Vector3d::UnitY(),
                 0.45};
  out.add_pair(toes, 0.015, 10);
}

}  // namespace

BodyField make_body_field(const Skeleton& skeleton) {
  Builder out;
  add_trunk(skeleton, out);
  add_shoulders_neck_head(skeleton, out);
  add_arm(skeleton, out);
  add_leg(skeleton, out);
  return BodyField(out.take());
}

}  // namespace sflsh::body::detail
