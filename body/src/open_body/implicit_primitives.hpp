#pragma once
// Implicit primitives of the open body: signed distance-like fields (negative inside, metres) with
// their gradients, and the polynomial smooth minimum that unites them.
//
// Exact distances where cheap (round cone); elsewhere the first-order estimate d = φ/|∇φ| of a
// normalised implicit φ (ellipsoid, torso loft), whose gradient is returned as ∇φ/|∇φ| — exact on the
// zero level set, which is all the mesher and the Newton projection need.
#include <Eigen/Core>

#include <array>
#include <vector>

namespace sflsh::body::detail {

/// A field value with its gradient.
struct FieldSample {
  double value = 0.0;        ///< signed distance estimate [m], negative inside
  Eigen::Vector3d gradient;  ///< ∂value/∂p (unit length on the surface for exact distances)
};

/// Polynomial (quadratic) smooth minimum of Quilez: smin(a,b,k) = min(a,b) − h²k/4,
/// h = max(k − |a − b|, 0)/k. `weight_b` receives ∂smin/∂b (∂smin/∂a = 1 − weight_b). k = 0 is min.
double smooth_min(double a, double b, double k, double& weight_b);

/// A cone with spherical caps: spheres (a, ra) and (b, rb) and their common tangent cone. The
/// cross-section may be squashed by `squash` ∈ (0, 1] along `squash_axis` (⟂ to b − a), which makes
/// flat capsules (hand, foot) at the cost of an approximate distance.
struct RoundCone {
  Eigen::Vector3d a, b;
  double ra = 0.0, rb = 0.0;
  Eigen::Vector3d squash_axis = Eigen::Vector3d::UnitY();
  double squash = 1.0;
};

/// An ellipsoid: centre, orthonormal axes (columns) and semi-axes [m].
struct Ellipsoid {
  Eigen::Vector3d center;
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d radii;
};

/// A vertical generalised cylinder for the trunk: elliptic cross-sections x²/a(y)² + (z − c(y))²/b(y)² = 1
/// interpolated by monotone cubic Hermite splines between knots, closed by smooth caps at both ends.
struct TorsoLoft {
  std::vector<double> y;    ///< knot heights [m], increasing
  std::vector<double> a;    ///< half-widths along x [m]
  std::vector<double> b;    ///< half-depths along z [m]
  std::vector<double> c;    ///< z of the section centre [m]
  double cap_blend = 0.03;  ///< smooth-max radius of the end caps [m]
};

/// A primitive after its shape constants are precomputed.
class Primitive {
 public:
  static Primitive round_cone(const RoundCone& cone);
  static Primitive ellipsoid(const Ellipsoid& ellipsoid);
  static Primitive torso_loft(const TorsoLoft& loft);

  /// Value and gradient at p.
  FieldSample evaluate(const Eigen::Vector3d& p) const;
  /// A lower bound of the primitive's value at p [m] (distance to the cone's axis segment or to the
  /// ellipsoid's centre less the largest radius; −∞ for the loft), tighter than the bounding sphere.
  double lower_bound(const Eigen::Vector3d& p) const;
  /// Centre and radius of a sphere that contains the primitive's inside [m].
  const Eigen::Vector3d& bound_center() const { return bound_center_; }
  double bound_radius() const { return bound_radius_; }

 private:
  enum class Kind { kRoundCone, kEllipsoid, kTorsoLoft };
  FieldSample evaluate_cone(const Eigen::Vector3d& p) const;
  FieldSample evaluate_ellipsoid(const Eigen::Vector3d& p) const;
  FieldSample evaluate_loft(const Eigen::Vector3d& p) const;

  Kind kind_ = Kind::kRoundCone;
  // Round cone: frame (axis u, squash axis v, w = u × v), length, radii, tangent-cone angle.
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d frame_ = Eigen::Matrix3d::Identity();  // columns u, v, w (ellipsoid: its axes)
  double length_ = 0.0, r1_ = 0.0, r2_ = 0.0, sin_phi_ = 0.0, cos_phi_ = 1.0, squash_ = 1.0;
  Eigen::Vector3d radii_ = Eigen::Vector3d::Ones();  // ellipsoid
  TorsoLoft loft_;
  std::array<std::vector<double>, 3> loft_slopes_;  // Hermite slopes of a, b, c per knot
  Eigen::Vector3d bound_center_ = Eigen::Vector3d::Zero();
  double bound_radius_ = 0.0;
  double largest_radius_ = 0.0;
};

}  // namespace sflsh::body::detail
