#include "implicit_primitives.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sflsh::body::detail {

double smooth_min(double a, double b, double k, double& weight_b) {
  if (k <= 0.0) {
    weight_b = b < a ? 1.0 : 0.0;
    return std::min(a, b);
  }
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  // For a < b: ∂/∂a = 1 − h/2, ∂/∂b = h/2 (and mirrored for b < a).
  weight_b = a < b ? 0.5 * h : 1.0 - 0.5 * h;
  return std::min(a, b) - 0.25 * h * h * k;
}

namespace {

/// Fritsch–Butland slopes of a monotone piecewise-cubic Hermite interpolant (flat at both ends).
std::vector<double> monotone_slopes(const std::vector<double>& x, const std::vector<double>& f) {
  const std::size_t n = x.size();
  std::vector<double> m(n, 0.0);
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const double h0 = x[k] - x[k - 1], h1 = x[k + 1] - x[k];
    const double d0 = (f[k] - f[k - 1]) / h0, d1 = (f[k + 1] - f[k]) / h1;
    if (d0 * d1 <= 0.0) continue;
    m[k] = 3.0 * (h0 + h1) / ((2.0 * h1 + h0) / d0 + (h1 + 2.0 * h0) / d1);
  }
  return m;
}

/// Knot interval k and local parameter t ∈ [0, 1] of y (clamped: t = 0 or 1 outside the knots).
void hermite_interval(const std::vector<double>& x, double y, std::size_t& k, double& t) {
  k = 0;
  if (y <= x.front()) {
    t = 0.0;
    return;
  }
  const std::size_t n = x.size();
  while (k + 2 < n && y > x[k + 1]) ++k;
  t = std::min((y - x[k]) / (x[k + 1] - x[k]), 1.0);
}

/// Value and y-derivative of the Hermite spline through (x, f) with slopes m on interval k at t
/// (zero slope outside the knots: the ends have zero Hermite slopes).
void hermite(const std::vector<double>& x, const std::vector<double>& f, const std::vector<double>& m, std::size_t k,
             double t, double& value, double& slope) {
  const double h = x[k + 1] - x[k];
  const double t2 = t * t, t3 = t2 * t;
  value = (2 * t3 - 3 * t2 + 1) * f[k] + (t3 - 2 * t2 + t) * h * m[k] + (-2 * t3 + 3 * t2) * f[k + 1] +
          (t3 - t2) * h * m[k + 1];
  slope = ((6 * t2 - 6 * t) * f[k] + (3 * t2 - 4 * t + 1) * h * m[k] + (-6 * t2 + 6 * t) * f[k + 1] +
           (3 * t2 - 2 * t) * h * m[k + 1]) /
          h;
}

/// √(a² + b²) without std::hypot's overflow guards (all lengths here are metres of order 1).
double length2d(double a, double b) { return std::sqrt(a * a + b * b); }

/// Smooth maximum smax(a,b,k) = −smin(−a,−b,k); `weight_b` = ∂smax/∂b.
double smooth_max(double a, double b, double k, double& weight_b) { return -smooth_min(-a, -b, k, weight_b); }

}  // namespace

Primitive Primitive::round_cone(const RoundCone& cone) {
  Primitive p;
  p.kind_ = Kind::kRoundCone;
  const Eigen::Vector3d axis = cone.b - cone.a;
  const double length = axis.norm();
  require(length > std::abs(cone.ra - cone.rb) + 1e-9, "open body: round cone with one sphere inside the other");
  require(cone.squash > 0.0 && cone.squash <= 1.0, "open body: round cone squash {} outside (0, 1]", cone.squash);
  const Eigen::Vector3d u = axis / length;
  Eigen::Vector3d v = cone.squash_axis - cone.squash_axis.dot(u) * u;
  require(v.norm() > 1e-6, "open body: round cone squash axis parallel to its axis");
  v.normalize();
  p.origin_ = cone.a;
  p.frame_.col(0) = u;
  p.frame_.col(1) = v;
  p.frame_.col(2) = u.cross(v);
  p.length_ = length;
  p.r1_ = cone.ra;
  p.r2_ = cone.rb;
  p.sin_phi_ = (cone.ra - cone.rb) / length;
  p.cos_phi_ = std::sqrt(1.0 - p.sin_phi_ * p.sin_phi_);
  p.squash_ = cone.squash;
  p.bound_center_ = 0.5 * (cone.a + cone.b);
  p.bound_radius_ = 0.5 * length + std::max(cone.ra, cone.rb);
  p.largest_radius_ = std::max(cone.ra, cone.rb);
  return p;
}

Primitive Primitive::ellipsoid(const Ellipsoid& e) {
  require(e.radii.minCoeff() > 0.0, "open body: ellipsoid with a non-positive semi-axis");
  Primitive p;
  p.kind_ = Kind::kEllipsoid;
  p.origin_ = e.center;
  p.frame_ = e.axes;
  p.radii_ = e.radii;
  p.bound_center_ = e.center;
  p.bound_radius_ = e.radii.maxCoeff();
  p.largest_radius_ = e.radii.maxCoeff();
  return p;
}

Primitive Primitive::torso_loft(const TorsoLoft& loft) {
  const std::size_t n = loft.y.size();
  require(n >= 2 && loft.a.size() == n && loft.b.size() == n && loft.c.size() == n,
          "open body: torso loft needs ≥ 2 knots with a, b, c each");
  for (std::size_t k = 0; k + 1 < n; ++k)
    require(loft.y[k + 1] > loft.y[k], "open body: torso loft knot heights must increase");
  Primitive p;
  p.kind_ = Kind::kTorsoLoft;
  p.loft_ = loft;
  p.loft_slopes_ = {monotone_slopes(loft.y, loft.a), monotone_slopes(loft.y, loft.b), monotone_slopes(loft.y, loft.c)};
  double widest = 0.0;
  for (std::size_t k = 0; k < n; ++k) widest = std::max({widest, loft.a[k], std::abs(loft.c[k]) + loft.b[k]});
  p.bound_center_ = Eigen::Vector3d(0.0, 0.5 * (loft.y.front() + loft.y.back()), 0.0);
  p.bound_radius_ = length2d(0.5 * (loft.y.back() - loft.y.front()), widest) + loft.cap_blend;
  return p;
}

double Primitive::lower_bound(const Eigen::Vector3d& p) const {
  switch (kind_) {
    case Kind::kRoundCone: {
      const double t = std::clamp(frame_.col(0).dot(p - origin_), 0.0, length_);
      return (p - origin_ - t * frame_.col(0)).norm() - largest_radius_;
    }
    case Kind::kEllipsoid:
      return (p - origin_).norm() - largest_radius_;
    case Kind::kTorsoLoft:
      break;
  }
  return -std::numeric_limits<double>::infinity();
}

FieldSample Primitive::evaluate(const Eigen::Vector3d& p) const {
  switch (kind_) {
    case Kind::kRoundCone:
      return evaluate_cone(p);
    case Kind::kEllipsoid:
      return evaluate_ellipsoid(p);
    case Kind::kTorsoLoft:
      return evaluate_loft(p);
  }
  return {};
}

FieldSample Primitive::evaluate_cone(const Eigen::Vector3d& p) const {
  // Local coordinates: t along the axis, (s_v, s_w) across it with s_v stretched by 1/squash.
  const Eigen::Vector3d local = frame_.transpose() * (p - origin_);
  const double t = local.x(), sv = local.y() / squash_, sw = local.z();
  const double rho = length2d(sv, sw);
  // In the (t, ρ) half-plane the tangent line touches both circles; s splits the three regions.
  const double s = t * cos_phi_ - rho * sin_phi_;
  double phi = 0.0, dt = 0.0, drho = 0.0;
  if (s < 0.0) {
    const double r = length2d(t, rho);
    phi = r - r1_;
    dt = r > 0.0 ? t / r : 0.0;
    drho = r > 0.0 ? rho / r : 0.0;
  } else if (s > length_ * cos_phi_) {
    const double r = length2d(t - length_, rho);
    phi = r - r2_;
    dt = r > 0.0 ? (t - length_) / r : 0.0;
    drho = r > 0.0 ? rho / r : 0.0;
  } else {
    phi = t * sin_phi_ + rho * cos_phi_ - r1_;
    dt = sin_phi_;
    drho = cos_phi_;
  }
  const double cv = rho > 0.0 ? sv / rho : 0.0, cw = rho > 0.0 ? sw / rho : 0.0;
  const Eigen::Vector3d grad_local(dt, drho * cv / squash_, drho * cw);
  const double norm = grad_local.norm();
  if (norm < 1e-12) return {phi, Eigen::Vector3d::Zero()};
  return {phi / norm, frame_ * (grad_local / norm)};
}

FieldSample Primitive::evaluate_ellipsoid(const Eigen::Vector3d& p) const {
  // φ = |q/r| − 1 with q in the ellipsoid frame; d = φ/|∇φ| = k0(k0 − 1)/k1 (Quilez' bound form).
  const Eigen::Vector3d q = frame_.transpose() * (p - origin_);
  const Eigen::Vector3d scaled = q.cwiseQuotient(radii_);
  const Eigen::Vector3d g = scaled.cwiseQuotient(radii_);
  const double k0 = scaled.norm(), k1 = g.norm();
  if (k1 < 1e-12) return {-radii_.minCoeff(), Eigen::Vector3d::Zero()};
  return {k0 * (k0 - 1.0) / k1, frame_ * (g / k1)};
}

FieldSample Primitive::evaluate_loft(const Eigen::Vector3d& p) const {
  double a, da, b, db, c, dc, t;
  std::size_t k;
  hermite_interval(loft_.y, p.y(), k, t);
  hermite(loft_.y, loft_.a, loft_slopes_[0], k, t, a, da);
  hermite(loft_.y, loft_.b, loft_slopes_[1], k, t, b, db);
  hermite(loft_.y, loft_.c, loft_slopes_[2], k, t, c, dc);
  // ρ(x, y, z) = |(x/a(y), (z − c(y))/b(y))|; the radial field is (ρ − 1)/|∇ρ|.
  const double u = p.x() / a, v = (p.z() - c) / b;
  const double rho = length2d(u, v);
  FieldSample out;
  if (rho < 1e-9) {
    out.value = -std::min(a, b);
    out.gradient.setZero();
  } else {
    const double du_dy = -u * da / a, dv_dy = -dc / b - v * db / b;
    const Eigen::Vector3d grad_rho(u / (a * rho), (u * du_dy + v * dv_dy) / rho, v / (b * rho));
    const double norm = grad_rho.norm();
    out.value = (rho - 1.0) / norm;
    out.gradient = grad_rho / norm;
  }
  // Rounded end caps: smooth intersection with the slab y0 ≤ y ≤ y1.
  double w = 0.0;
  out.value = smooth_max(out.value, loft_.y.front() - p.y(), loft_.cap_blend, w);
  out.gradient = (1.0 - w) * out.gradient + w * Eigen::Vector3d(0.0, -1.0, 0.0);
  out.value = smooth_max(out.value, p.y() - loft_.y.back(), loft_.cap_blend, w);
  out.gradient = (1.0 - w) * out.gradient + w * Eigen::Vector3d(0.0, 1.0, 0.0);
  return out;
}

}  // namespace sflsh::body::detail
