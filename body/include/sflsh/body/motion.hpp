#pragma once
// Motions: sequences of SMPL poses θ(t) and root translations at a fixed frame rate.
// Procedural versions of the five DYNA motion kinds (docs/architecture.md §2) and AMASS .npz files.
#include <sflsh/body/skinning.hpp>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::body {

/// Bounds a motion file must stay within (checked by load_amass before anything large is allocated):
/// frame rates (the file's and the requested one) in [1, 10000] Hz, at most one hour and at most
/// 1,000,000 frames (before and after resampling), joint angles within ±1000 rad and root
/// translations within ±10 km. Anything beyond is not motion capture data.
inline constexpr double kMinMotionFps = 1.0;
inline constexpr double kMaxMotionFps = 10000.0;
inline constexpr double kMaxMotionSeconds = 3600.0;
inline constexpr std::size_t kMaxMotionFrames = 1000000;
inline constexpr double kMaxPoseRadians = 1000.0;
inline constexpr double kMaxRootMetres = 10000.0;

struct Motion {
  std::string name;
  std::string source;                  ///< "procedural" or the file path it was read from
  double fps = 60.0;                   ///< frames per second of `poses` / `trans`
  std::vector<Pose> poses;             ///< θ per frame (72 axis-angle values)
  std::vector<Eigen::Vector3d> trans;  ///< root translation per frame [m], in the body's frame
  /// Rotation applied to posed positions to bring them into the world frame (Y up). Identity for
  /// procedural motions; AMASS data is Z-up, so loading it sets a −90° rotation about X.
  Eigen::Matrix3d world_from_body = Eigen::Matrix3d::Identity();
  /// Procedural motions: the time offset they were generated with [s] (make_procedural_motion), so that
  /// offset_motion composes; 0 for data motions.
  double time_offset = 0.0;

  std::size_t num_frames() const { return poses.size(); }
  double duration() const { return num_frames() > 1 ? static_cast<double>(num_frames() - 1) / fps : 0.0; }
  double time(std::size_t frame) const { return static_cast<double>(frame) / fps; }
  /// Throws sflsh::Error when sizes disagree, fps is not positive, a value is not finite, there are
  /// no frames, or world_from_body is not a rotation.
  void validate() const;
};

/// Per-joint spherical interpolation of two poses along the shortest arc (u ∈ [0, 1], u = 0 gives a):
/// each joint's axis-angle vector is turned into a unit quaternion, q_b is negated when q_a·q_b < 0,
/// and the result is returned as axis-angle with angle ∈ [0, π].
Pose slerp_pose(const Pose& a, const Pose& b, double u);

/// The world_from_body of AMASS data: −90° about X, mapping AMASS's up axis +Z to +Y.
Eigen::Matrix3d amass_world_from_body();

/// The procedural motion kinds, in DYNA order: one_leg_jump, running_on_spot, shake_hips
/// (training) and jiggle_on_toes, shake_shoulders (testing).
const std::vector<std::string>& procedural_motion_names();
/// Procedural showcase motions outside the DYNA set (not in procedural_motion_names(), accepted by
/// make_procedural_motion and load_motion): "dance" — a T = 2 s looping groove (hips sway, knees bounce
/// on the beat with the feet planted, arms swing, torso twists), ease-in from rest, C^∞ afterwards.
const std::vector<std::string>& showcase_motion_names();
/// One-line description of a procedural or showcase motion (for `sflsh motion list`).
std::string procedural_motion_description(const std::string& name);
/// Period [s] of a procedural motion's steady part when it is periodic by construction (dance: 2 s),
/// else 0. Throws for an unknown name.
double procedural_motion_period(const std::string& name);

/// Generates a procedural motion at `fps`. frames ≤ 0 selects the motion's default length.
/// `time_offset` [s]: periodic motions (procedural_motion_period > 0) still leave the rest pose with
/// their ease-in at t = 0 but run their steady part shifted by the offset (a crowd in different phases);
/// the others are the motion from t + offset on (held at the rest pose where t + offset < 0).
/// Throws sflsh::Error for an unknown name (listing the known ones).
Motion make_procedural_motion(const std::string& name, double fps = 60.0, int frames = 0, double time_offset = 0.0);

/// Frames first … first + frames − 1 of make_procedural_motion(name, fps, first + frames), sample for sample,
/// without generating the frames before `first`: memory and time grow with `frames` only, however far into the
/// motion it starts (first ≥ 0, frames ≥ 1, first + frames < 2⁵³).
Motion procedural_motion_window(const std::string& name, double fps, long long first, int frames);
/// Whether `name` is a procedural or showcase motion (make_procedural_motion accepts it).
bool is_procedural_motion(const std::string& name);

/// The motion started `seconds` later, same fps and frame count: a procedural motion (source
/// "procedural", a known name) is regenerated with that time_offset (see make_procedural_motion); data
/// motions show the input at t_i + seconds clamped to [0, duration] (per-joint slerp between frames,
/// exact copies for whole-frame offsets).
Motion offset_motion(const Motion& motion, double seconds);

/// Reads an AMASS .npz (poses T×156 or T×72, trans T×3, mocap_framerate or mocap_frame_rate)
/// and maps it onto SMPL's 24 joints (SMPL-H body joints 0..21; SMPL hand joints 22, 23 get zero).
/// The result is resampled to `fps` (quaternion slerp per joint, linear translation); a file whose
/// rate equals `fps` is used frame for frame. world_from_body is amass_world_from_body() unless the
/// file carries "sflsh_world_from_body" (written by save_amass). Errors name the file and the key
/// ("<file>: <key>: found, expected"); the bounds above are checked before the arrays are converted.
Motion load_amass(const std::filesystem::path& path, double fps = 60.0);

/// Writes a motion in AMASS layout (poses T×72, trans T×3, mocap_framerate, gender) atomically, plus
/// the motion's world_from_body as "sflsh_world_from_body" (3×3) so that a round trip through
/// load_amass keeps the frame (files without that key are taken as AMASS's Z-up).
void save_amass(const std::filesystem::path& path, const Motion& motion);

/// Resamples a motion to a new frame rate (slerp per joint, linear translation). Output frame i is at
/// t = i / fps and the output covers the input's duration: floor(duration · fps) + 1 frames. Returns
/// the motion unchanged (apart from fps) when the rates agree within 1e-9 relative.
Motion resample(const Motion& motion, double fps);

/// Loads a motion by name (procedural) or by path (a .npz file). frames > 0 sets the length of a
/// procedural motion and truncates a file's motion (a warning is logged when the file is shorter).
/// `time_offset` [s] ≠ 0 starts it later (offset_motion; procedural motions via make_procedural_motion).
Motion load_motion(const std::string& name_or_path, double fps = 60.0, int frames = 0, double time_offset = 0.0);

}  // namespace sflsh::body
