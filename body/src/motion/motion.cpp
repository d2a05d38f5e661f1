// Motion::validate, the procedural-motion registry, and load_motion.
#include "procedural.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/input_file.hpp>
#include <sflsh/core/log.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace sflsh::body {

namespace motion_detail {

std::span<const ProceduralSpec> procedural_specs() {
  static constexpr std::array<ProceduralSpec, 5> specs{{
      {"one_leg_jump", "hopping on the left leg at 2 hops/s, right leg lifted; ballistic flight, ≈4 g landings", 4.0,
       &sample_one_leg_jump},
      {"running_on_spot", "jogging in place at 2.7 steps/s: hips to 45°, knees to 90°, 4 cm bounce, arms swinging", 4.0,
       &sample_running_on_spot},
      {"shake_hips", "pelvis roll ±17° (yaw ±8°) at 2 Hz, spine counter-rotating, feet planted", 4.0,
       &sample_shake_hips},
      {"jiggle_on_toes", "bouncing on the balls of the feet at 2.75 Hz, ≈3 cm up and down, ankles plantar-flexing", 4.0,
       &sample_jiggle_on_toes},
      {"shake_shoulders", "alternating shoulder shimmy: collars ±12° forward/back at 3.5 Hz, arms hanging", 4.0,
       &sample_shake_shoulders},
  }};
  return specs;
}

std::span<const ProceduralSpec> showcase_specs() {
  static const std::array<ProceduralSpec, 1> specs{{
      {"dance",
       "looping groove at 120 bpm (2 s bar): hips sway ±4.5 cm, knees bounce on the beat, arms swing, torso twists",
       4.5, [](double t) { return sample_dance(t, 0.0); }, &sample_dance, dance_period()},
  }};
  return specs;
}

PoseSample scaled_from_rest(const PoseSample& steady, double weight) {
  PoseSample out;
  out.theta = weight * steady.theta;
  out.trans = weight * steady.trans;
  return out;
}

namespace {

const ProceduralSpec* find_spec(const std::string& name) {
  for (const ProceduralSpec& spec : procedural_specs())
    if (spec.name == name) return &spec;
  for (const ProceduralSpec& spec : showcase_specs())
    if (spec.name == name) return &spec;
  return nullptr;
}

std::string known_names() {
  std::string out;
  for (const std::string& n : procedural_motion_names()) out += (out.empty() ? "" : ", ") + n;
  for (const std::string& n : showcase_motion_names()) out += ", " + n;
  return out;
}

}  // namespace
}  // namespace motion_detail

void Motion::validate() const {
  const std::string who = name.empty() ? std::string("motion") : fmt::format("motion '{}'", name);
  require(std::isfinite(fps) && fps > 0.0, "{}: fps must be a positive number, got {}", who, fps);
  require(!poses.empty(), "{}: has no frames", who);
  require(poses.size() == trans.size(), "{}: {} poses but {} root translations", who, poses.size(), trans.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    require(poses[i].allFinite(), "{}: frame {} has a non-finite pose value", who, i);
    require(trans[i].allFinite(), "{}: frame {} has a non-finite root translation", who, i);
  }
  require(world_from_body.allFinite() &&
              (world_from_body * world_from_body.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
              world_from_body.determinant() > 0.0,
          "{}: world_from_body is not a rotation matrix", who);
}

const std::vector<std::string>& procedural_motion_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& spec : motion_detail::procedural_specs()) out.emplace_back(spec.name);
    return out;
  }();
  return names;
}

const std::vector<std::string>& showcase_motion_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& spec : motion_detail::showcase_specs()) out.emplace_back(spec.name);
    return out;
  }();
  return names;
}

double procedural_motion_period(const std::string& name) {
  const motion_detail::ProceduralSpec* spec = motion_detail::find_spec(name);
  require(spec != nullptr, "unknown procedural motion '{}' (known: {})", name, motion_detail::known_names());
  return spec->period;
}

std::string procedural_motion_description(const std::string& name) {
  const motion_detail::ProceduralSpec* spec = motion_detail::find_spec(name);
  require(spec != nullptr, "unknown procedural motion '{}' (known: {})", name, motion_detail::known_names());
  return std::string(spec->description);
}

namespace {

/// Frames first … first + count − 1 of a procedural motion (frame i at t = i / fps).
Motion sample_procedural(const motion_detail::ProceduralSpec& spec, const std::string& name, double fps,
                         long long first, long long count, double time_offset) {
  Motion motion;
  motion.name = name;
  motion.source = "procedural";
  motion.fps = fps;
  motion.time_offset = time_offset;
  motion.poses.reserve(static_cast<std::size_t>(count));
  motion.trans.reserve(static_cast<std::size_t>(count));
  for (long long i = first; i < first + count; ++i) {
    const double t = static_cast<double>(i) / fps;
    // Periodic motions shift the phase of their steady part; the others start later (held at rest
    // before t = 0 for negative offsets).
    const motion_detail::PoseSample s =
        spec.sample_offset ? spec.sample_offset(t, time_offset) : spec.sample(std::max(0.0, t + time_offset));
    motion.poses.push_back(s.theta);
    motion.trans.push_back(s.trans);
  }
  return motion;
}

}  // namespace

bool is_procedural_motion(const std::string& name) { return motion_detail::find_spec(name) != nullptr; }

Motion procedural_motion_window(const std::string& name, double fps, long long first, int frames) {
  const motion_detail::ProceduralSpec* spec = motion_detail::find_spec(name);
  require(spec != nullptr, "unknown procedural motion '{}' (known: {})", name, motion_detail::known_names());
  require(std::isfinite(fps) && fps > 0.0, "motion '{}': fps must be a positive number, got {}", name, fps);
  require(first >= 0 && frames >= 1 && first < (1LL << 53) - frames,
          "motion '{}': frames {} … {} are not a valid window (first >= 0, at least one frame)", name, first,
          first + frames - 1);
  return sample_procedural(*spec, name, fps, first, frames, 0.0);
}

Motion make_procedural_motion(const std::string& name, double fps, int frames, double time_offset) {
  const motion_detail::ProceduralSpec* spec = motion_detail::find_spec(name);
  require(spec != nullptr, "unknown procedural motion '{}' (known: {})", name, motion_detail::known_names());
  require(std::isfinite(fps) && fps > 0.0, "motion '{}': fps must be a positive number, got {}", name, fps);
  require(std::isfinite(time_offset), "motion '{}': the time offset must be finite, got {}", name, time_offset);
  const long count = frames > 0 ? frames : std::max(1L, std::lround(spec->default_seconds * fps));
  return sample_procedural(*spec, name, fps, 0, count, time_offset);
}

Motion offset_motion(const Motion& motion, double seconds) {
  require(std::isfinite(seconds), "motion '{}': the time offset must be finite, got {}", motion.name, seconds);
  motion.validate();
  if (motion.source == "procedural" && motion_detail::find_spec(motion.name) != nullptr) {
    Motion out = make_procedural_motion(motion.name, motion.fps, static_cast<int>(motion.num_frames()),
                                        motion.time_offset + seconds);
    out.world_from_body = motion.world_from_body;
    return out;
  }
  // Data: frame i shows the input at t_i + seconds, clamped to [0, duration] (slerp between frames).
  Motion out = motion;
  const std::size_t n = motion.num_frames();
  for (std::size_t i = 0; i < n; ++i) {
    const double s = std::clamp((motion.time(i) + seconds) * motion.fps, 0.0, static_cast<double>(n - 1));
    const double nearest = std::round(s);
    if (std::abs(s - nearest) <= 1e-9) {  // on a frame (offsets of whole frames are exact copies)
      const auto k = static_cast<std::size_t>(nearest);
      out.poses[i] = motion.poses[k];
      out.trans[i] = motion.trans[k];
      continue;
    }
    const auto k = static_cast<std::size_t>(std::floor(s));
    const double u = s - static_cast<double>(k);
    out.poses[i] = slerp_pose(motion.poses[k], motion.poses[k + 1], u);
    out.trans[i] = (1.0 - u) * motion.trans[k] + u * motion.trans[k + 1];
  }
  return out;
}

Motion load_motion(const std::string& name_or_path, double fps, int frames, double time_offset) {
  if (motion_detail::find_spec(name_or_path) != nullptr)
    return make_procedural_motion(name_or_path, fps, frames, time_offset);
  const std::filesystem::path path(name_or_path);
  std::error_code ec;
  require(std::filesystem::exists(path, ec), "motion '{}': not a procedural motion ({}) and no such file", name_or_path,
          motion_detail::known_names());
  require_input_file(path, "an AMASS motion .npz file (or a procedural motion name)");
  Motion motion = load_amass(path, fps);
  if (frames > 0) {
    const auto wanted = static_cast<std::size_t>(frames);
    if (wanted < motion.num_frames()) {
      motion.poses.resize(wanted);
      motion.trans.resize(wanted);
    } else if (wanted > motion.num_frames()) {
      logger()->warn("motion '{}': {} frames requested, the file has {} at {} fps; using all of them", name_or_path,
                     frames, motion.num_frames(), motion.fps);
    }
  }
  return time_offset != 0.0 ? offset_motion(motion, time_offset) : motion;
}

}  // namespace sflsh::body
