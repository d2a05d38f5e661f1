// Frame-rate conversion of motions: per-joint quaternion slerp (shortest arc), linear translation.
#include "rig.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::body {

namespace {

/// Shortest-arc slerp of unit quaternions: q(u) = (sin((1−u)Ω) q₀ + sin(uΩ) q₁) / sin Ω with
/// cos Ω = |q₀·q₁| (q₁ negated when the dot product is negative, which is the same rotation).
Eigen::Quaterniond slerp_shortest(const Eigen::Quaterniond& q0, Eigen::Quaterniond q1, double u) {
  double c = q0.dot(q1);
  if (c < 0.0) {
    q1.coeffs() = -q1.coeffs();
    c = -c;
  }
  if (c > 1.0 - 1e-12) {  // nearly equal: normalized lerp is exact to rounding
    Eigen::Quaterniond q(q0.coeffs() + u * (q1.coeffs() - q0.coeffs()));
    return q.normalized();
  }
  const double omega = std::acos(std::min(c, 1.0));
  const double s = std::sin(omega);
  const double w0 = std::sin((1.0 - u) * omega) / s, w1 = std::sin(u * omega) / s;
  return Eigen::Quaterniond(w0 * q0.coeffs() + w1 * q1.coeffs()).normalized();
}

}  // namespace

Pose slerp_pose(const Pose& a, const Pose& b, double u) {
  using motion_detail::exp_rotation;
  using motion_detail::log_rotation;
  Pose out;
  for (int k = 0; k < kNumJoints; ++k) {
    const Eigen::Quaterniond qa = exp_rotation(a.segment<3>(3 * k));
    const Eigen::Quaterniond qb = exp_rotation(b.segment<3>(3 * k));
    out.segment<3>(3 * k) = log_rotation(slerp_shortest(qa, qb, u));
  }
  return out;
}

Motion resample(const Motion& motion, double fps) {
  require(std::isfinite(fps) && fps > 0.0, "resample '{}': fps must be a positive number, got {}", motion.name, fps);
  require(!motion.poses.empty() && motion.poses.size() == motion.trans.size() && motion.fps > 0.0,
          "resample '{}': the motion is empty or inconsistent ({} poses, {} translations, {} fps)", motion.name,
          motion.poses.size(), motion.trans.size(), motion.fps);
  Motion out = motion;
  out.fps = fps;
  if (std::abs(fps - motion.fps) <= 1e-9 * motion.fps) return out;

  const std::size_t n_in = motion.num_frames();
  // floor(duration · fps) + 1 frames; the 1e-9 guards rates whose ratio is not exact in binary.
  const double span = static_cast<double>(n_in - 1) * fps / motion.fps;
  require(std::isfinite(span) && span < static_cast<double>(kMaxMotionFrames),
          "resample '{}': {} frames at {:g} fps become {:g} frames at {:g} fps, above the limit of {} frames",
          motion.name, n_in, motion.fps, std::floor(span) + 1.0, fps, kMaxMotionFrames);
  const auto n_out = static_cast<std::size_t>(std::floor(span + 1e-9)) + 1;
  out.poses.resize(n_out);
  out.trans.resize(n_out);
  for (std::size_t i = 0; i < n_out; ++i) {
    const double s = static_cast<double>(i) * motion.fps / fps;  // position in input frames
    std::size_t k = std::min(static_cast<std::size_t>(std::floor(s)), n_in - 1);
    double u = s - static_cast<double>(k);
    if (k + 1 >= n_in) {  // at (or rounding past) the last input frame
      k = n_in - 1;
      u = 0.0;
    }
    if (u <= 1e-12) {
      out.poses[i] = motion.poses[k];
      out.trans[i] = motion.trans[k];
      continue;
    }
    out.poses[i] = slerp_pose(motion.poses[k], motion.poses[k + 1], u);
    out.trans[i] = (1.0 - u) * motion.trans[k] + u * motion.trans[k + 1];
  }
  return out;
}

}  // namespace sflsh::body
