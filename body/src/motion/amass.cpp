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
constexpr std::size_t kBodyPoseWidth = 66;               // root + 21 body joints
constexpr const char* kFrameKey = "sflsh_world_from_body";

/// Reads a numeric member as doubles, with errors naming the file and the key.
std::vector<double> read_numeric(const npz::Reader& reader, const std::string& key, npz::Array& array) {
  array = reader.read(key);
  require(array.is_numeric(), "{}: key '{}' has dtype {}, expected a numeric array", reader.path().string(), key,
          array.dtype());
  return array.to_doubles();
}

/// First non-finite entry of a row-major (rows × cols) array, as "frame r, column c".
void require_finite(const std::vector<double>& values, std::size_t cols, const std::string& file,
                    const std::string& key) {
  for (std::size_t i = 0; i < values.size(); ++i)
    require(std::isfinite(values[i]), "{}: key '{}' holds a non-finite value ({}) at frame {}, column {}", file, key,
            values[i], i / cols, i % cols);
}

double read_frame_rate(const npz::Reader& reader) {
  const std::string file = reader.path().string();
  std::string key;
  if (reader.has("mocap_framerate")) key = "mocap_framerate";
  else if (reader.has("mocap_frame_rate")) key = "mocap_frame_rate";
  else throw_error("{}: missing key 'mocap_framerate' (or 'mocap_frame_rate'), the capture rate [1/s]", file);
  npz::Array array;
  const std::vector<double> v = read_numeric(reader, key, array);
  require(v.size() == 1, "{}: key '{}' has shape {}, expected a scalar (0-d or 1 element)", file, key,
          array.shape_string());
  require(std::isfinite(v[0]) && v[0] > 0.0, "{}: key '{}' is {}, expected a positive frame rate [1/s]", file, key,
          v[0]);
  return v[0];
}

Eigen::Matrix3d read_world_from_body(const npz::Reader& reader) {
  if (!reader.has(kFrameKey)) return amass_world_from_body();
  const std::string file = reader.path().string();
  npz::Array array;
  const std::vector<double> v = read_numeric(reader, kFrameKey, array);
  require(array.shape == std::vector<std::size_t>{3, 3}, "{}: key '{}' has shape {}, expected (3, 3)", file,
          kFrameKey, array.shape_string());
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = v[static_cast<std::size_t>(3 * i + j)];
  require(r.allFinite() && (r * r.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6 && r.determinant() > 0.0,
          "{}: key '{}' is not a rotation matrix", file, kFrameKey);
  return r;
}

}  // namespace

Eigen::Matrix3d amass_world_from_body() {
  // R_x(−90°) maps (0, 0, 1) to (0, 1, 0): AMASS's up becomes our up.
  return Eigen::AngleAxisd(-0.5 * 3.14159265358979323846, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

Motion load_amass(const std::filesystem::path& path, double fps) {
  require(std::isfinite(fps) && fps > 0.0, "{}: requested fps must be a positive number, got {}", path.string(), fps);
  const npz::Reader reader(path);  // "<path>: file not found" / "not a readable .npz (zip) archive"
  const std::string file = path.string();

  require(reader.has("poses"), "{}: missing key 'poses', expected (T, 156) SMPL+H or (T, 72) SMPL axis-angle poses",
          file);
  npz::Array poses_array;
  const std::vector<double> poses = read_numeric(reader, "poses", poses_array);
  const auto& ps = poses_array.shape;
  require(ps.size() == 2 && (ps[1] == kSmplhPoseWidth || ps[1] == kSmplPoseWidth),
          "{}: key 'poses' has shape {}, expected (T, 156) or (T, 72)", file, poses_array.shape_string());
  const std::size_t frames = ps[0], width = ps[1];
  require(frames >= 1, "{}: key 'poses' has shape {}, expected at least 1 frame", file, poses_array.shape_string());
  require_finite(poses, width, file, "poses");

  require(reader.has("trans"), "{}: missing key 'trans', expected (T, 3) root translations [m]", file);
  npz::Array trans_array;
  const std::vector<double> trans = read_numeric(reader, "trans", trans_array);
  require(trans_array.shape.size() == 2 && trans_array.shape[1] == 3,
          "{}: key 'trans' has shape {}, expected (T, 3)", file, trans_array.shape_string());
  require(trans_array.shape[0] == frames, "{}: key 'trans' has {} rows but 'poses' has {}, expected equal counts",
          file, trans_array.shape[0], frames);
  require_finite(trans, 3, file, "trans");

  const double rate = read_frame_rate(reader);
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
