// A scene body's motion: the named motion (or the still rest pose), started `motion_offset` seconds in, with
// the approach keyframes added to its root translation (scene_internal.hpp).
#include "bodies/scene_internal.hpp"

#include <sflsh/core/error.hpp>

#include <cmath>

namespace sflsh::scene::detail {

namespace {

/// Root offset of the approach at time t: eased (smoothstep) between consecutive keys, so the velocity is
/// zero at every key and the translation is C¹; held before the first and after the last key.
Eigen::Vector3d approach_at(const std::vector<SceneKeyframe>& keys, double t) {
  if (keys.empty()) return Eigen::Vector3d::Zero();
  if (t <= keys.front().t) return keys.front().position;
  if (t >= keys.back().t) return keys.back().position;
  std::size_t k = 1;
  while (keys[k].t < t) ++k;
  const double u = (t - keys[k - 1].t) / (keys[k].t - keys[k - 1].t);
  const double s = u * u * (3.0 - 2.0 * u);
  return (1.0 - s) * keys[k - 1].position + s * keys[k].position;
}

}  // namespace

body::Motion scene_motion(const std::string& name, double offset, const std::vector<SceneKeyframe>& approach,
                          double fps, int frames) {
  require(frames >= 1, "scene motion: at least one frame, got {}", frames);
  require(std::isfinite(offset) && offset >= 0.0 && offset <= kMaxMotionOffset,
          "motion '{}': motion_offset {} s is outside [0, {}] s", name, offset, kMaxMotionOffset);
  // Whole frames skipped; the bound above keeps this far inside long long (≤ 3600 s × 10000 fps).
  const long long skip = std::llround(offset * fps);
  body::Motion motion;
  if (name == "rest") {
    motion.name = "rest";
    motion.source = "procedural";
    motion.fps = fps;
    motion.poses.assign(static_cast<std::size_t>(frames), body::Pose::Zero());
    motion.trans.assign(static_cast<std::size_t>(frames), Eigen::Vector3d::Zero());
  } else if (body::is_procedural_motion(name)) {
    // Only the frames asked for, sampled where the offset puts them: O(frames), not O(offset · fps).
    motion = body::procedural_motion_window(name, fps, skip, frames);
  } else {
    motion = body::load_motion(name, fps, 0);
    if (std::abs(motion.fps - fps) > 1e-9 * fps) motion = body::resample(motion, fps);
    require(static_cast<long long>(motion.num_frames()) > skip, "motion '{}': the offset {} s is beyond its {} frames",
            name, offset, motion.num_frames());
    motion.poses.erase(motion.poses.begin(), motion.poses.begin() + skip);
    motion.trans.erase(motion.trans.begin(), motion.trans.begin() + skip);
    if (static_cast<int>(motion.num_frames()) > frames) {
      motion.poses.resize(static_cast<std::size_t>(frames));
      motion.trans.resize(static_cast<std::size_t>(frames));
    }
    // A recorded motion shorter than the scene holds its last pose.
    while (static_cast<int>(motion.num_frames()) < frames) {
      motion.poses.push_back(motion.poses.back());
      motion.trans.push_back(motion.trans.back());
    }
  }
  for (std::size_t f = 0; f < motion.num_frames(); ++f) motion.trans[f] += approach_at(approach, motion.time(f));
  motion.validate();
  return motion;
}

}  // namespace sflsh::scene::detail
