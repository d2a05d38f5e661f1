// Analytic obstacle shapes: half-space, sphere, box, capsule (the triangle mesh is triangle_mesh.cpp).
// Every φ is the exact Euclidean signed distance, so its Hessian is the curvature of the level set:
// for φ = |q − c(q)| with c(q) the closest point of a convex feature, ∇φ = n = (q − c)/|q − c| and
// ∇²φ = (∂c-free directions − n nᵀ)/|q − c|, i.e. (P − n nᵀ)/|q − c| with P the projector on the
// directions in which c(q) does not move (all three at a point, the normal plane of a segment, …).
#include <sflsh/core/error.hpp>
#include <sflsh/scene/obstacle.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sflsh::scene {

namespace {

constexpr double kTiny = 1e-12;  // [m] below this a distance counts as zero (the direction is undefined)

}  // namespace

// ===  Aabb  =================================================================================

double Aabb::distance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d gap = (lower - p).cwiseMax(p - upper).cwiseMax(0.0);
  return gap.norm();
}

double Aabb::distance(const Aabb& other) const {
  const Eigen::Vector3d gap = (other.lower - upper).cwiseMax(lower - other.upper).cwiseMax(0.0);
  return gap.norm();
}

// ===  Obstacle  =============================================================================

double Obstacle::distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const {
  const double phi = local_distance(pose_.to_local(p), gradient, hessian);
  const Eigen::Matrix3d& R = pose_.rotation;
  if (gradient) *gradient = R * *gradient;
  if (hessian) *hessian = R * *hessian * R.transpose();
  return phi;
}

Aabb Obstacle::bounds() const {
  const Aabb local = local_bounds();
  Aabb world;
  if (local.empty()) return world;
  if (!local.lower.allFinite() || !local.upper.allFinite()) {
    // Rotating an unbounded box leaves no finite axis in general: report it unbounded.
    world.lower.setConstant(-std::numeric_limits<double>::infinity());
    world.upper.setConstant(std::numeric_limits<double>::infinity());
    return world;
  }
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d q((corner & 1) ? local.upper.x() : local.lower.x(),
                            (corner & 2) ? local.upper.y() : local.lower.y(),
                            (corner & 4) ? local.upper.z() : local.lower.z());
    world.extend(pose_.to_world(q));
  }
  return world;
}

Surface Obstacle::surface(int n_segments) const {
  require(n_segments >= 3, "obstacle surface: n_segments must be at least 3 (got {})", n_segments);
  Surface s = local_surface(n_segments);
  for (Eigen::Index i = 0; i < s.vertices.rows(); ++i)
    s.vertices.row(i) = pose_.to_world(s.vertices.row(i).transpose()).transpose();
  return s;
}

Surface revolve_profile(const std::vector<Eigen::Vector2d>& profile, int n_segments) {
  require(profile.size() >= 3 && n_segments >= 3, "revolve_profile: needs ≥ 3 profile points and ≥ 3 segments");
  const int rings = static_cast<int>(profile.size()) - 2;  // without the two poles
  const int n = n_segments;
  Surface s;
  s.vertices.resize(2 + rings * n, 3);
  s.vertices.row(0) << 0.0, 0.0, profile.front().y();
  for (int j = 0; j < rings; ++j) {
    const Eigen::Vector2d& rz = profile[static_cast<std::size_t>(j + 1)];
    for (int k = 0; k < n; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / n;
      s.vertices.row(1 + j * n + k) << rz.x() * std::cos(angle), rz.x() * std::sin(angle), rz.y();
    }
  }
  const int top = 1 + rings * n;
  s.vertices.row(top) << 0.0, 0.0, profile.back().y();
  s.triangles.resize(2 * n + 2 * n * (rings - 1), 3);
  int f = 0;
  auto ring = [n](int j, int k) { return 1 + j * n + (k % n); };
  for (int k = 0; k < n; ++k) s.triangles.row(f++) << 0, ring(0, k + 1), ring(0, k);  // bottom cap, facing −z
  for (int j = 0; j + 1 < rings; ++j)
    for (int k = 0; k < n; ++k) {
      s.triangles.row(f++) << ring(j, k), ring(j, k + 1), ring(j + 1, k + 1);
      s.triangles.row(f++) << ring(j, k), ring(j + 1, k + 1), ring(j + 1, k);
    }
  for (int k = 0; k < n; ++k) s.triangles.row(f++) << ring(rings - 1, k), ring(rings - 1, k + 1), top;
  return s;
}

// ===  HalfSpace  ============================================================================

HalfSpace::HalfSpace(const Eigen::Vector3d& normal, double offset, double display_size)
    : normal_(normal), offset_(offset), display_size_(display_size) {
  require(normal.allFinite() && normal.norm() > kTiny, "half-space: the normal must be a non-zero finite vector");
  require(std::isfinite(offset) && display_size > 0.0, "half-space: offset must be finite and display_size > 0");
  normal_.normalize();
}

double HalfSpace::local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const {
  if (gradient) *gradient = normal_;
  if (hessian) hessian->setZero();
  return normal_.dot(q) - offset_;
}

Aabb HalfSpace::local_bounds() const {
  Aabb b;
  b.lower.setConstant(-std::numeric_limits<double>::infinity());
  b.upper.setConstant(std::numeric_limits<double>::infinity());
  return b;
}

Surface HalfSpace::local_surface(int /*n_segments*/) const {
  // Two triangles facing +n (out of the solid) around the plane point closest to the local origin.
  const Eigen::Vector3d centre = offset_ * normal_;
  const Eigen::Vector3d u = normal_.unitOrthogonal();
  const Eigen::Vector3d v = normal_.cross(u);
  const double h = 0.5 * display_size_;
  Surface s;
  s.vertices.resize(4, 3);
  s.vertices.row(0) = (centre - h * u - h * v).transpose();
  s.vertices.row(1) = (centre + h * u - h * v).transpose();
  s.vertices.row(2) = (centre + h * u + h * v).transpose();
  s.vertices.row(3) = (centre - h * u + h * v).transpose();
  s.triangles.resize(2, 3);
  s.triangles << 0, 1, 2, 0, 2, 3;  // (u × v) = n: counter-clockwise seen from outside
  return s;
}

// ===  Sphere  ===============================================================================

Sphere::Sphere(double radius) : radius_(radius) {
  require(std::isfinite(radius) && radius > 0.0, "sphere: radius must be positive (got {})", radius);
}

double Sphere::local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const {
  const double rho = q.norm();
  if (rho < kTiny) {  // the centre: any direction; ∇²φ is unbounded, report 0
    if (gradient) *gradient = Eigen::Vector3d::UnitZ();
    if (hessian) hessian->setZero();
    return -radius_;
  }
  const Eigen::Vector3d n = q / rho;
  if (gradient) *gradient = n;
  if (hessian) *hessian = (Eigen::Matrix3d::Identity() - n * n.transpose()) / rho;
  return rho - radius_;
}

Aabb Sphere::local_bounds() const {
  Aabb b;
  b.lower.setConstant(-radius_);
  b.upper.setConstant(radius_);
  return b;
}

Surface Sphere::local_surface(int n_segments) const {
  const int m = std::max(2, n_segments / 2);
  std::vector<Eigen::Vector2d> profile;
  for (int j = 0; j <= m; ++j) {
    const double theta = std::numbers::pi * j / m;
    profile.emplace_back(radius_ * std::sin(theta), -radius_ * std::cos(theta));
  }
  profile.front().x() = 0.0;
  profile.back().x() = 0.0;
  return revolve_profile(profile, n_segments);
}

// ===  Box  ==================================================================================

Box::Box(const Eigen::Vector3d& half_extent) : half_extent_(half_extent) {
  require(half_extent.allFinite() && half_extent.minCoeff() > 0.0, "box: half extents must be positive");
}

double Box::local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const {
  const Eigen::Vector3d sign = q.unaryExpr([](double x) { return x >= 0.0 ? 1.0 : -1.0; });
  const Eigen::Vector3d r = q.cwiseAbs() - half_extent_;  // per-axis distance outside the slab
  if (r.maxCoeff() > 0.0) {
    // Outside: the closest point clamps the outside axes; φ = |max(r, 0)|.
    const Eigen::Vector3d d = r.cwiseMax(0.0);
    const double phi = d.norm();
    const Eigen::Vector3d n = sign.cwiseProduct(d) / phi;
    if (gradient) *gradient = n;
    if (hessian) {
      const Eigen::Matrix3d P = (r.array() > 0.0).cast<double>().matrix().asDiagonal();
      *hessian = (P - n * n.transpose()) / phi;
    }
    return phi;
  }
  // Inside: the nearest face.
  Eigen::Index axis = 0;
  const double phi = r.maxCoeff(&axis);
  if (gradient) *gradient = sign(axis) * Eigen::Vector3d::Unit(axis);
  if (hessian) hessian->setZero();
  return phi;
}

Aabb Box::local_bounds() const {
  Aabb b;
  b.lower = -half_extent_;
  b.upper = half_extent_;
  return b;
}

Surface Box::local_surface(int /*n_segments*/) const {
  Surface s;
  s.vertices.resize(8, 3);
  for (int c = 0; c < 8; ++c)
    s.vertices.row(c) << ((c & 1) ? 1 : -1) * half_extent_.x(), ((c & 2) ? 1 : -1) * half_extent_.y(),
        ((c & 4) ? 1 : -1) * half_extent_.z();
  // Corner c has bits (x, y, z); each face as two counter-clockwise triangles seen from outside.
  s.triangles.resize(12, 3);
  s.triangles << 0, 2, 3, 0, 3, 1,  // −z
      4, 5, 7, 4, 7, 6,             // +z
      0, 1, 5, 0, 5, 4,             // −y
      2, 6, 7, 2, 7, 3,             // +y
      0, 4, 6, 0, 6, 2,             // −x
      1, 3, 7, 1, 7, 5;             // +x
  return s;
}

// ===  Capsule  ==============================================================================

Capsule::Capsule(double radius, double half_length) : radius_(radius), half_length_(half_length) {
  require(std::isfinite(radius) && radius > 0.0, "capsule: radius must be positive (got {})", radius);
  require(std::isfinite(half_length) && half_length >= 0.0, "capsule: half_length must be ≥ 0 (got {})", half_length);
}

double Capsule::local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const {
  const double zc = std::clamp(q.z(), -half_length_, half_length_);
  const Eigen::Vector3d v = q - Eigen::Vector3d(0.0, 0.0, zc);
  const double rho = v.norm();
  if (rho < kTiny) {  // on the segment
    if (gradient) *gradient = Eigen::Vector3d::UnitX();
    if (hessian) hessian->setZero();
    return -radius_;
  }
  const Eigen::Vector3d n = v / rho;
  if (gradient) *gradient = n;
  if (hessian) {
    Eigen::Matrix3d P = Eigen::Matrix3d::Identity();
    if (std::abs(q.z()) < half_length_) P(2, 2) = 0.0;  // beside the segment c(q) slides along z
    *hessian = (P - n * n.transpose()) / rho;
  }
  return rho - radius_;
}

Aabb Capsule::local_bounds() const {
  Aabb b;
  b.lower = Eigen::Vector3d(-radius_, -radius_, -radius_ - half_length_);
  b.upper = -b.lower;
  return b;
}

Surface Capsule::local_surface(int n_segments) const {
  const int m = std::max(1, n_segments / 4);  // latitude steps per hemisphere
  std::vector<Eigen::Vector2d> profile;
  for (int j = 0; j <= m; ++j) {
    const double theta = 0.5 * std::numbers::pi * j / m;
    profile.emplace_back(radius_ * std::sin(theta), -half_length_ - radius_ * std::cos(theta));
  }
  for (int j = (half_length_ > 0.0 ? 0 : 1); j <= m; ++j) {
    const double theta = 0.5 * std::numbers::pi * (1.0 + static_cast<double>(j) / m);
    profile.emplace_back(radius_ * std::sin(theta), half_length_ - radius_ * std::cos(theta));
  }
  profile.front().x() = 0.0;
  profile.back().x() = 0.0;
  return revolve_profile(profile, n_segments);
}

}  // namespace sflsh::scene
