// AMASS .npz motions (docs/physics.md §3.3): poses (T×156 SMPL+H or T×72 SMPL), trans (T×3),
// mocap_framerate or mocap_frame_rate. AMASS is Z-up; SMPL+H poses map onto SMPL as
// θ = [poses[:, :66], 0₆] (SMPL's hand joints 22, 23 do not exist in SMPL+H).
#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/npz.hpp>

#include <Eigen/Geometry>

#include <cmath>

namespace sflsh::body {

namespace {

constexpr std::size_t kSmplhPoseWidth = 156;
constexpr std::size_t kSmplPoseWidth = 3 * kNumJoints;  // 72
constexpr std::size_t kBodyPoseWidth = 66;              // root + 21 body joints
constexpr const char* kFrameKey = "sflsh_world_from_body";

/// "<file>: <key>: dtype …, expected …" unless the array holds floats or integers (bool and strings are
/// not motion data).
void require_number_kind(const npz::Array& array, const std::string& file, const std::string& key,
                         const char* expected) {
  require(array.kind == 'f' || array.kind == 'i' || array.kind == 'u', "{}: {}: dtype {} ({}), expected {}", file, key,
          array.dtype(),
          array.kind == 'b'    ? "bool"
          : array.is_numeric() ? "numbers"
                               : "not numeric",
          expected);
}

/// Reads a member holding floats or integers as doubles, with errors naming the file and the key.
std::vector<double> read_numbers(const npz::Reader& reader, const std::string& key, npz::Array& array,
                                 const char* expected) {
  array = reader.read(key);
  require_number_kind(array, reader.path().string(), key, expected);
  return array.to_doubles();
}

/// First value of a row-major (rows × cols) array that is not finite or beyond ±bound, as
/// "<file>: <key>: <value> at frame r, column c is …".
void require_bounded(const std::vector<double>& values, std::size_t cols, const std::string& file,
                     const std::string& key, double bound, const char* unit, const char* meaning) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    require(std::isfinite(values[i]),
            "{}: {}: non-finite value ({}) at frame {}, column {}, expected {} within ±{:g} {}", file, key, values[i],
            i / cols, i % cols, meaning, bound, unit);
    require(std::abs(values[i]) <= bound, "{}: {}: {} {} at frame {}, column {} is beyond ±{:g} {}, not {}", file, key,
            values[i], unit, i / cols, i % cols, bound, unit, meaning);
  }
}

double read_frame_rate(const npz::Reader& reader) {
  const std::string file = reader.path().string();
  std::string key;
  if (reader.has("mocap_framerate"))
    key = "mocap_framerate";
  else if (reader.has("mocap_frame_rate"))
    key = "mocap_frame_rate";
  else
    throw_error("{}: missing key 'mocap_framerate' (or 'mocap_frame_rate'), the capture rate [Hz]", file);
  npz::Array array;
  const std::vector<double> v = read_numbers(reader, key, array, "a frame rate in Hz (float)");
  require(v.size() == 1, "{}: {}: shape {}, expected a scalar (0-d or 1 element)", file, key, array.shape_string());
  require(std::isfinite(v[0]) && v[0] >= kMinMotionFps && v[0] <= kMaxMotionFps,
          "{}: {}: {:g} Hz is outside [{:g}, {:g}] Hz", file, key, v[0], kMinMotionFps, kMaxMotionFps);
  return v[0];
}

Eigen::Matrix3d read_world_from_body(const npz::Reader& reader) {
  if (!reader.has(kFrameKey)) return amass_world_from_body();
  const std::string file = reader.path().string();
  npz::Array array;
  const std::vector<double> v = read_numbers(reader, kFrameKey, array, "a 3×3 rotation matrix (float)");
  require(array.shape == std::vector<std::size_t>{3, 3}, "{}: {}: shape {}, expected (3, 3)", file, kFrameKey,
          array.shape_string());
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = v[static_cast<std::size_t>(3 * i + j)];
  require(r.allFinite() && (r * r.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6 && r.determinant() > 0.0,
          "{}: {}: not a rotation matrix, expected R with RᵀR = I and det R = 1", file, kFrameKey);
  return r;
}

}  // namespace

Eigen::Matrix3d amass_world_from_body() {
  // R_x(−90°) maps (0, 0, 1) to (0, 1, 0): AMASS's up becomes our up.
  return Eigen::AngleAxisd(-0.5 * 3.14159265358979323846, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

Motion load_amass(const std::filesystem::path& path, double fps) {
  require(std::isfinite(fps) && fps >= kMinMotionFps && fps <= kMaxMotionFps,
          "{}: requested fps {:g} is outside [{:g}, {:g}] Hz", path.string(), fps, kMinMotionFps, kMaxMotionFps);
  const npz::Reader reader(path);  // "<path>: file not found" / "not a readable .npz (zip) archive"
  const std::string file = path.string();

  // The rate first: it bounds the duration before the large arrays are converted.
  const double rate = read_frame_rate(reader);

  require(reader.has("poses"), "{}: missing key 'poses', expected (T, 156) SMPL+H or (T, 72) SMPL axis-angle poses",
          file);
  npz::Array poses_array = reader.read("poses");
  require_number_kind(poses_array, file, "poses", "float axis-angle poses [rad]");
  const auto& ps = poses_array.shape;
  require(ps.size() == 2 && (ps[1] == kSmplhPoseWidth || ps[1] == kSmplPoseWidth),
          "{}: poses: shape {}, expected (T, 156) or (T, 72)", file, poses_array.shape_string());
  const std::size_t frames = ps[0], width = ps[1];
  require(frames >= 1, "{}: poses: shape {}, expected at least 1 frame", file, poses_array.shape_string());
  require(frames <= kMaxMotionFrames, "{}: poses: {} frames is above the limit of {} frames", file, frames,
          kMaxMotionFrames);
  const double duration = static_cast<double>(frames - 1) / rate;
  require(duration <= kMaxMotionSeconds, "{}: poses: {} frames at {:g} Hz last {:g} s, above the limit of {:g} s", file,
          frames, rate, duration, kMaxMotionSeconds);
  const double resampled = std::floor(duration * fps + 1e-9) + 1.0;
  require(resampled <= static_cast<double>(kMaxMotionFrames),
          "{}: poses: {:g} s resampled to {:g} fps is {:g} frames, above the limit of {} frames", file, duration, fps,
          resampled, kMaxMotionFrames);
  const std::vector<double> poses = poses_array.to_doubles();
  require_bounded(poses, width, file, "poses", kMaxPoseRadians, "rad", "a joint angle");

  require(reader.has("trans"), "{}: missing key 'trans', expected (T, 3) root translations [m]", file);
  npz::Array trans_array;
  const std::vector<double> trans = read_numbers(reader, "trans", trans_array, "float root translations [m]");
  require(trans_array.shape.size() == 2 && trans_array.shape[1] == 3, "{}: trans: shape {}, expected (T, 3)", file,
          trans_array.shape_string());
  require(trans_array.shape[0] == frames, "{}: trans: {} rows but 'poses' has {}, expected equal counts", file,
          trans_array.shape[0], frames);
  require_bounded(trans, 3, file, "trans", kMaxRootMetres, "m", "a root translation");

  for (const char* ignored : {"gender", "betas", "dmpls"})
    if (reader.has(ignored)) logger()->debug("{}: ignoring key '{}'", file, ignored);

  Motion motion;
  motion.name = path.stem().string();
  motion.source = file;
  motion.fps = rate;
  motion.world_from_body = read_world_from_body(reader);
  motion.poses.resize(frames);
  motion.trans.resize(frames);
  const std::size_t used = width == kSmplhPoseWidth ? kBodyPoseWidth : kSmplPoseWidth;
  for (std::size_t t = 0; t < frames; ++t) {
    Pose theta = Pose::Zero();
    for (std::size_t c = 0; c < used; ++c) theta(static_cast<Eigen::Index>(c)) = poses[t * width + c];
    motion.poses[t] = theta;
    motion.trans[t] = Eigen::Vector3d(trans[3 * t], trans[3 * t + 1], trans[3 * t + 2]);
  }
  logger()->debug("{}: {} frames at {} fps ({} pose columns)", file, frames, rate, width);
  return resample(motion, fps);
}

void save_amass(const std::filesystem::path& path, const Motion& motion) {
  motion.validate();
  const std::size_t n = motion.num_frames();
  std::vector<double> poses(n * kSmplPoseWidth), trans(n * 3), frame(9);
  for (std::size_t t = 0; t < n; ++t) {
    for (std::size_t c = 0; c < kSmplPoseWidth; ++c)
      poses[t * kSmplPoseWidth + c] = motion.poses[t](static_cast<Eigen::Index>(c));
    for (std::size_t c = 0; c < 3; ++c) trans[t * 3 + c] = motion.trans[t](static_cast<Eigen::Index>(c));
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) frame[static_cast<std::size_t>(3 * i + j)] = motion.world_from_body(i, j);
  npz::write(path, {{"poses", npz::make_f64({n, kSmplPoseWidth}, poses)},
                    {"trans", npz::make_f64({n, 3}, trans)},
                    {"mocap_framerate", npz::make_scalar(motion.fps)},
                    {"gender", npz::make_string("neutral")},
                    {kFrameKey, npz::make_f64({3, 3}, frame)}});
}

}  // namespace sflsh::body
