#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_motion.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace sflsh::scene {

// ===  KeyframeMotion  =======================================================================

KeyframeMotion::KeyframeMotion(std::vector<Keyframe> keys, KeyframeInterpolation interpolation)
    : keys_(std::move(keys)), interpolation_(interpolation) {
  require(!keys_.empty(), "keyframe motion: needs at least one key");
  for (std::size_t i = 0; i < keys_.size(); ++i) {
    require(std::isfinite(keys_[i].t) && keys_[i].position.allFinite() && keys_[i].rotation.coeffs().allFinite() &&
                keys_[i].rotation.norm() > 0.0,
            "keyframe motion: key {} has a non-finite time, position or rotation", i);
    require(i == 0 || keys_[i].t > keys_[i - 1].t, "keyframe motion: key times must increase (key {} at t = {})", i,
            keys_[i].t);
    keys_[i].rotation.normalize();
  }
}

namespace {

/// The segment [i, i+1] containing t and the local parameter s ∈ [0, 1]; i = −1 before, n−1 after.
std::pair<int, double> locate(const std::vector<Keyframe>& keys, double t) {
  const int n = static_cast<int>(keys.size());
  if (n == 1 || t <= keys.front().t) return {-1, 0.0};
  if (t >= keys.back().t) return {n - 1, 0.0};
  const auto it = std::upper_bound(keys.begin(), keys.end(), t, [](double v, const Keyframe& k) { return v < k.t; });
  const int i = static_cast<int>(it - keys.begin()) - 1;
  return {i, (t - keys[static_cast<std::size_t>(i)].t) /
                 (keys[static_cast<std::size_t>(i) + 1].t - keys[static_cast<std::size_t>(i)].t)};
}

}  // namespace

Pose KeyframeMotion::pose(double t) const {
  const auto [i, s] = locate(keys_, t);
  const int n = static_cast<int>(keys_.size());
  Pose pose;
  if (i < 0 || i >= n - 1) {
    const Keyframe& k = i < 0 ? keys_.front() : keys_.back();
    pose.rotation = k.rotation.toRotationMatrix();
    pose.translation = k.position;
    return pose;
  }
  const Keyframe& k0 = keys_[static_cast<std::size_t>(i)];
  const Keyframe& k1 = keys_[static_cast<std::size_t>(i) + 1];
  pose.rotation = k0.rotation.slerp(s, k1.rotation).toRotationMatrix();
  if (interpolation_ == KeyframeInterpolation::linear) {
    pose.translation = (1.0 - s) * k0.position + s * k1.position;
    return pose;
  }
  // Cubic Hermite on [t_i, t_{i+1}] with tangents m (per unit time), h = t_{i+1} − t_i.
  auto tangent = [&](int j) -> Eigen::Vector3d {
    if (j == 0 || j == n - 1) return Eigen::Vector3d::Zero();
    const Keyframe& a = keys_[static_cast<std::size_t>(j) - 1];
    const Keyframe& b = keys_[static_cast<std::size_t>(j) + 1];
    return (b.position - a.position) / (b.t - a.t);
  };
  const double h = k1.t - k0.t;
  const double s2 = s * s, s3 = s2 * s;
  pose.translation = (2 * s3 - 3 * s2 + 1) * k0.position + (s3 - 2 * s2 + s) * h * tangent(i) +
                     (-2 * s3 + 3 * s2) * k1.position + (s3 - s2) * h * tangent(i + 1);
  return pose;
}

Eigen::Vector3d KeyframeMotion::velocity(double t) const {
  const auto [i, s] = locate(keys_, t);
  const int n = static_cast<int>(keys_.size());
  if (i < 0 || i >= n - 1) return Eigen::Vector3d::Zero();
  const Keyframe& k0 = keys_[static_cast<std::size_t>(i)];
  const Keyframe& k1 = keys_[static_cast<std::size_t>(i) + 1];
  const double h = k1.t - k0.t;
  if (interpolation_ == KeyframeInterpolation::linear) return (k1.position - k0.position) / h;
  auto tangent = [&](int j) -> Eigen::Vector3d {
    if (j == 0 || j == n - 1) return Eigen::Vector3d::Zero();
    const Keyframe& a = keys_[static_cast<std::size_t>(j) - 1];
    const Keyframe& b = keys_[static_cast<std::size_t>(j) + 1];
    return (b.position - a.position) / (b.t - a.t);
  };
  const double s2 = s * s;
  return ((6 * s2 - 6 * s) * k0.position + (3 * s2 - 4 * s + 1) * h * tangent(i) + (-6 * s2 + 6 * s) * k1.position +
          (3 * s2 - 2 * s) * h * tangent(i + 1)) /
         h;
}

// ===  FreeMotion  ===========================================================================

FreeMotion::FreeMotion(double mass, const Eigen::Vector3d& gravity, const Pose& initial,
                       const Eigen::Vector3d& velocity, double t0)
    : mass_(mass), gravity_(gravity), pose_(initial), velocity_(velocity), t_(t0) {
  require(std::isfinite(mass) && mass > 0.0, "free motion: mass must be positive (got {})", mass);
  require(gravity.allFinite() && velocity.allFinite() && initial.translation.allFinite() && std::isfinite(t0),
          "free motion: gravity, velocity, position and t0 must be finite");
}

// (m + dt² k) v_{n+1} = m v_n + dt (m g + F_n): the reaction linearized as F_n − k dt v_{n+1} (k = 0: explicit).
Eigen::Vector3d FreeMotion::predicted_velocity(double dt) const {
  return (mass_ * velocity_ + dt * (mass_ * gravity_ + force_)) / (mass_ + dt * dt * contact_stiffness_);
}

void FreeMotion::set_contact_stiffness(double k) {
  require(std::isfinite(k) && k >= 0.0, "free motion: contact stiffness must be ≥ 0 (got {})", k);
  contact_stiffness_ = k;
}

Pose FreeMotion::pose(double t) const {
  // Idempotent: a substep solved again (refinement) asks for the same pose.
  const double dt = t - t_;
  Pose p = pose_;
  if (dt > 0.0) p.translation += dt * predicted_velocity(dt);
  return p;
}

void FreeMotion::commit(double t, const Eigen::Vector3d& force) {
  require(force.allFinite(), "free motion: non-finite contact force at t = {}", t);
  const double dt = t - t_;
  if (dt > 0.0) {
    velocity_ = predicted_velocity(dt);
    pose_.translation += dt * velocity_;  // x_{n+1} = x_n + dt v_{n+1}
    t_ = t;
  }
  force_ = force;  // F_{n+1}, used by the next step
}

}  // namespace sflsh::scene
