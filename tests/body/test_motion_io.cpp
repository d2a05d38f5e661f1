// Motion validation, loading by name or path, AMASS files and resampling.
// conventions checked with forward kinematics on a synthetic skeleton), AMASS .npz files
// (layout, resampling, errors), and resampling.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

// White-box: the private curve and rig helpers of the procedural motions.
#include "../../body/src/motion/curves.hpp"
#include "../../body/src/motion/rig.hpp"
#include "angles.hpp"
#include "error_of.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

namespace sflsh::body {
namespace {

namespace md = motion_detail;
using sflsh::testing::kDeg;

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / ("sflsh_test_motion_io_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

/// Removes this process's temporary folder after all tests.
class TempDirCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(
        std::filesystem::temp_directory_path() / ("sflsh_test_motion_io_" + std::to_string(::getpid())), ec);
  }
};
[[maybe_unused]] ::testing::Environment* const kTempDirCleanup =
    ::testing::AddGlobalTestEnvironment(new TempDirCleanup);

using sflsh::testing::error_of;

// ---------------------------------------------------------------------------------------------
// Motion::validate and load_motion

TEST(MotionValidate, RejectsInconsistentMotions) {
  Motion m = make_procedural_motion("shake_hips", 60.0, 5);
  EXPECT_NO_THROW(m.validate());
  Motion bad = m;
  bad.trans.pop_back();
  EXPECT_THROW(bad.validate(), Error);
  bad = m;
  bad.fps = 0.0;
  EXPECT_THROW(bad.validate(), Error);
  bad = m;
  bad.poses[2](5) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(error_of([&] { bad.validate(); }).find("frame 2"), std::string::npos);
  bad = m;
  bad.world_from_body(0, 0) = 2.0;
  EXPECT_THROW(bad.validate(), Error);
}

TEST(MotionLoad, ByNameOrPath) {
  const Motion a = load_motion("jiggle_on_toes", 30.0, 0);
  EXPECT_EQ(a.num_frames(), 120u);
  EXPECT_EQ(load_motion("jiggle_on_toes", 60.0, 50).num_frames(), 50u);
  const auto path = temp_dir() / "walk.npz";
  save_amass(path, make_procedural_motion("shake_hips", 60.0, 30));
  EXPECT_EQ(load_motion(path.string(), 60.0, 0).num_frames(), 30u);
  EXPECT_EQ(load_motion(path.string(), 60.0, 12).num_frames(), 12u);
  EXPECT_EQ(load_motion(path.string(), 60.0, 100).num_frames(), 30u);  // shorter file: all of it
  const std::string msg = error_of([] { load_motion("no_such_motion.npz"); });
  EXPECT_NE(msg.find("motion 'no_such_motion.npz': not a procedural motion (one_leg_jump, running_on_spot, "
                     "shake_hips, jiggle_on_toes, shake_shoulders, dance) and no such file"),
            std::string::npos)
      << msg;
}

// ---------------------------------------------------------------------------------------------
// AMASS files

/// Deterministic pseudo-random poses: rows × width, angles up to ±1.2 rad per component.
std::vector<double> test_poses(std::size_t rows, std::size_t width) {
  std::vector<double> v(rows * width);
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = 1.2 * std::sin(0.37 * static_cast<double>(i) + 0.1 * static_cast<double>(i % 7));
  return v;
}

std::vector<double> test_trans(std::size_t rows) {
  std::vector<double> v(rows * 3);
  for (std::size_t i = 0; i < rows; ++i) v[3 * i] = 0.01 * i, v[3 * i + 1] = -0.02 * i, v[3 * i + 2] = 0.9 + 0.001 * i;
  return v;
}

using Members = std::vector<std::pair<std::string, npz::Array>>;

Members amass_members(std::size_t rows, std::size_t width, double rate) {
  return {{"poses", npz::make_f64({rows, width}, test_poses(rows, width))},
          {"trans", npz::make_f64({rows, 3}, test_trans(rows))},
          {"mocap_framerate", npz::make_scalar(rate)},
          {"gender", npz::make_string("female")},
          {"betas", npz::make_f64({16}, std::vector<double>(16, 0.1))}};
}

std::filesystem::path write_members(const std::string& name, const Members& members) {
  const auto path = temp_dir() / name;
  npz::write(path, members);
  return path;
}

TEST(AmassMotion, SmplhAt120ResampledTo60) {
  const std::size_t rows = 11;
  const auto path = write_members("smplh_120.npz", amass_members(rows, 156, 120.0));
  const Motion m = load_amass(path, 60.0);
  ASSERT_EQ(m.num_frames(), 6u);  // duration 10/120 s → frames at 0, 1/60, …, 5/60
  EXPECT_DOUBLE_EQ(m.fps, 60.0);
  EXPECT_EQ(m.name, "smplh_120");
  EXPECT_EQ(m.source, path.string());
  const auto poses = test_poses(rows, 156);
  const auto trans = test_trans(rows);
  for (std::size_t i = 0; i < m.num_frames(); ++i) {
    for (int c = 0; c < 66; ++c) EXPECT_DOUBLE_EQ(m.poses[i](c), poses[2 * i * 156 + static_cast<std::size_t>(c)]);
    for (int c = 66; c < 72; ++c) EXPECT_EQ(m.poses[i](c), 0.0) << "hand joints 22, 23 are zero";
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(m.trans[i](c), trans[2 * i * 3 + static_cast<std::size_t>(c)]);
  }
  // AMASS is Z-up: +Z (the body's up) maps to +Y.
  EXPECT_LT((m.world_from_body * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitY()).norm(), 1e-15);
  EXPECT_NEAR(m.world_from_body.determinant(), 1.0, 1e-15);
  EXPECT_NO_THROW(m.validate());
}

TEST(AmassMotion, SmplhAt100MatchesSlerpBetweenFrames) {
  const std::size_t rows = 21;
  const auto path = write_members("smplh_100.npz", amass_members(rows, 156, 100.0));
  const Motion m = load_amass(path, 60.0);
  ASSERT_EQ(m.num_frames(), 13u);  // floor(20 · 0.6) + 1
  const auto poses = test_poses(rows, 156);
  const auto trans = test_trans(rows);
  // Frame 1 at t = 1/60 s lies 2/3 of the way from input frame 1 to 2; compare with Eigen's slerp.
  const double u = 100.0 / 60.0 - 1.0;
  for (int k = 0; k < 22; ++k) {
    Eigen::Vector3d w1, w2;
    for (int c = 0; c < 3; ++c) w1(c) = poses[156 + 3 * k + c], w2(c) = poses[2 * 156 + 3 * k + c];
    const Eigen::Quaterniond q1(Eigen::AngleAxisd(w1.norm(), w1.normalized()));
    const Eigen::Quaterniond q2(Eigen::AngleAxisd(w2.norm(), w2.normalized()));
    const Eigen::Quaterniond expected = q1.slerp(u, q2);
    const Eigen::Quaterniond got = md::exp_rotation(m.poses[1].segment<3>(3 * k));
    EXPECT_NEAR(std::abs(expected.dot(got)), 1.0, 1e-12) << "joint " << k;
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.trans[1](c), (1 - u) * trans[3 + c] + u * trans[6 + c], 1e-15);
}

TEST(AmassMotion, SmplAt60UsedFrameForFrame) {
  const std::size_t rows = 7;
  Members members = amass_members(rows, 72, 60.0);
  members[2] = {"mocap_frame_rate", npz::make_f64({1}, {60.0})};  // the SMPL-X-era key, 1-element array
  const auto path = write_members("smpl_60.npz", members);
  const Motion m = load_amass(path, 60.0);
  ASSERT_EQ(m.num_frames(), rows);
  const auto poses = test_poses(rows, 72);
  for (std::size_t i = 0; i < rows; ++i)
    for (int c = 0; c < 72; ++c) EXPECT_EQ(m.poses[i](c), poses[i * 72 + static_cast<std::size_t>(c)]);
}

TEST(AmassMotion, SaveLoadRoundTrip) {
  const Motion original = make_procedural_motion("one_leg_jump", 60.0, 40);
  const auto path = temp_dir() / "roundtrip.npz";
  save_amass(path, original);
  const npz::Reader reader(path);
  EXPECT_EQ(reader.read("poses").shape, (std::vector<std::size_t>{40, 72}));
  EXPECT_EQ(reader.read("trans").shape, (std::vector<std::size_t>{40, 3}));
  EXPECT_TRUE(reader.read("mocap_framerate").shape.empty());
  EXPECT_EQ(reader.read("gender").to_string(), "neutral");
  const Motion loaded = load_amass(path, 60.0);
  ASSERT_EQ(loaded.num_frames(), original.num_frames());
  for (std::size_t i = 0; i < loaded.num_frames(); ++i) {
    EXPECT_EQ(loaded.poses[i], original.poses[i]);
    EXPECT_EQ(loaded.trans[i], original.trans[i]);
  }
  EXPECT_TRUE(loaded.world_from_body.isIdentity(0.0));  // the frame survives the round trip
}

TEST(AmassMotion, MalformedFilesNameFileAndKey) {
  struct Case {
    std::string file, expect;
    std::function<void(Members&)> edit;
  };
  const std::vector<Case> cases = {
      {"no_poses.npz", "missing key 'poses'", [](Members& m) { m.erase(m.begin()); }},
      {"wide.npz", "poses: shape (10, 100), expected (T, 156) or (T, 72)",
       [](Members& m) {
         m[0].second = npz::make_f64({10, 100}, std::vector<double>(1000, 0.0));
       }},
      {"flat.npz", "poses: shape (156,)",
       [](Members& m) { m[0].second = npz::make_f64({156}, std::vector<double>(156, 0.0)); }},
      {"empty.npz", "poses: shape (0, 156), expected at least 1 frame",
       [](Members& m) {
         m[0].second = npz::make_f64({0, 156}, {});
       }},
      {"rows.npz", "trans: 9 rows but 'poses' has 10",
       [](Members& m) {
         m[1].second = npz::make_f64({9, 3}, std::vector<double>(27, 0.0));
       }},
      {"trans_shape.npz", "trans: shape (10, 2), expected (T, 3)",
       [](Members& m) {
         m[1].second = npz::make_f64({10, 2}, std::vector<double>(20, 0.0));
       }},
      {"no_trans.npz", "missing key 'trans'", [](Members& m) { m.erase(m.begin() + 1); }},
      {"rate0.npz", "mocap_framerate: 0 Hz is outside [1, 10000] Hz",
       [](Members& m) { m[2].second = npz::make_scalar(0.0); }},
      {"rate_neg.npz", "mocap_framerate: -30 Hz is outside [1, 10000] Hz",
       [](Members& m) { m[2].second = npz::make_scalar(-30.0); }},
      {"no_rate.npz", "missing key 'mocap_framerate' (or 'mocap_frame_rate')",
       [](Members& m) { m.erase(m.begin() + 2); }},
      {"rate_text.npz", "mocap_framerate: dtype <U2", [](Members& m) { m[2].second = npz::make_string("60"); }},
      {"nan.npz", "poses: non-finite value (nan) at frame 3, column 5",
       [](Members& m) {
         auto v = test_poses(10, 156);
         v[3 * 156 + 5] = std::numeric_limits<double>::quiet_NaN();
         m[0].second = npz::make_f64({10, 156}, v);
       }},
      {"inf_trans.npz", "trans: non-finite value",
       [](Members& m) {
         auto v = test_trans(10);
         v[4] = std::numeric_limits<double>::infinity();
         m[1].second = npz::make_f64({10, 3}, v);
       }},
  };
  for (const Case& c : cases) {
    Members members = amass_members(10, 156, 120.0);
    c.edit(members);
    const auto path = write_members(c.file, members);
    const std::string msg = error_of([&] { load_amass(path, 60.0); });
    EXPECT_NE(msg.find(path.string()), std::string::npos) << c.file << ": " << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.file << ": " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << c.file << ": " << msg;
  }
  // Not a zip archive, and no file at all.
  const auto junk = temp_dir() / "junk.npz";
  std::ofstream(junk) << "this is not a zip archive";
  std::string msg = error_of([&] { load_amass(junk, 60.0); });
  EXPECT_NE(msg.find(junk.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("zip"), std::string::npos) << msg;
  msg = error_of([&] { load_amass(temp_dir() / "absent.npz", 60.0); });
  EXPECT_NE(msg.find("absent.npz"), std::string::npos) << msg;
}

/// An array of raw element bytes (bool, float16) with the given shape.
npz::Array raw_array(char kind, std::size_t itemsize, std::vector<std::size_t> shape, std::vector<std::uint8_t> bytes) {
  npz::Array a;
  a.kind = kind;
  a.itemsize = itemsize;
  a.shape = std::move(shape);
  a.bytes = std::move(bytes);
  return a;
}

TEST(AmassMotion, AbsurdRatesTypesAndValuesAreRefusedBeforeAllocating) {
  struct Case {
    std::string file, expect;
    std::function<void(Members&)> edit;
    double fps = 60.0;
  };
  const std::vector<Case> cases = {
      // 1e-9 Hz once made resampling allocate ~1e10 frames; 5e-324 was taken as one frame.
      {"rate_tiny.npz", "mocap_framerate: 1e-09 Hz is outside [1, 10000] Hz",
       [](Members& m) { m[2].second = npz::make_scalar(1e-9); }},
      {"rate_denormal.npz", "mocap_framerate: 4.94066e-324 Hz is outside [1, 10000] Hz",
       [](Members& m) { m[2].second = npz::make_scalar(5e-324); }},
      {"rate_huge.npz", "mocap_framerate: 100000 Hz is outside [1, 10000] Hz",
       [](Members& m) { m[2].second = npz::make_scalar(1e5); }},
      {"rate_inf.npz", "mocap_framerate: inf Hz is outside [1, 10000] Hz",
       [](Members& m) { m[2].second = npz::make_scalar(std::numeric_limits<double>::infinity()); }},
      {"poses_bool.npz", "poses: dtype |b1 (bool), expected float axis-angle poses [rad]",
       [](Members& m) {
         m[0].second = raw_array('b', 1, {10, 156}, std::vector<std::uint8_t>(1560, 1));
       }},
      {"poses_huge.npz", "poses: 1e+300 rad at frame 0, column 4 is beyond ±1000 rad, not a joint angle",
       [](Members& m) {
         auto v = test_poses(10, 156);
         v[4] = 1e300;
         m[0].second = npz::make_f64({10, 156}, v);
       }},
      {"trans_far.npz", "trans: 100000 m at frame 2, column 1 is beyond ±10000 m, not a root translation",
       [](Members& m) {
         auto v = test_trans(10);
         v[7] = 1e5;
         m[1].second = npz::make_f64({10, 3}, v);
       }},
      {"too_long.npz", "poses: 3602 frames at 1 Hz last 3601 s, above the limit of 3600 s",
       [](Members& m) { m = amass_members(3602, 72, 1.0); }},
      {"too_many_resampled.npz",
       "poses: 2999 s resampled to 10000 fps is 2.999e+07 frames, above the limit of 1000000 frames",
       [](Members& m) { m = amass_members(3000, 72, 1.0); }, 10000.0},
      {"fps_request.npz", "requested fps 0.5 is outside [1, 10000] Hz", [](Members&) {}, 0.5},
  };
  for (const Case& c : cases) {
    Members members = amass_members(10, 156, 120.0);
    c.edit(members);
    const auto path = write_members(c.file, members);
    const std::string msg = error_of([&] { load_amass(path, c.fps); });
    EXPECT_EQ(msg.rfind(path.string() + ": ", 0), 0u) << c.file << ": " << msg;  // starts with the file
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.file << ": " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << c.file << ": " << msg;
  }
  // The bounds themselves are accepted; so is the older key spelling.
  Members edge = amass_members(4, 72, 10000.0);
  edge[2].first = "mocap_frame_rate";
  EXPECT_EQ(load_amass(write_members("edge.npz", edge), 10000.0).num_frames(), 4u);
}

TEST(AmassMotion, Float16PosesAreReadExactly) {
  // 0x3C00 = 1, 0xB800 = -0.5, 0x3555 = 0.333251953125, 0x0001 = 2^-24 (smallest subnormal).
  const std::uint16_t halves[4] = {0x3C00, 0xB800, 0x3555, 0x0001};
  std::vector<std::uint8_t> bytes(2 * 72 * 2, 0);
  for (std::size_t i = 0; i < 4; ++i) std::memcpy(bytes.data() + 2 * (72 + i), &halves[i], 2);  // frame 1, columns 0..3
  Members members = amass_members(2, 72, 60.0);
  members[0].second = raw_array('f', 2, {2, 72}, bytes);
  const Motion m = load_amass(write_members("half.npz", members), 60.0);
  ASSERT_EQ(m.num_frames(), 2u);
  EXPECT_EQ(m.poses[0], Pose::Zero());
  EXPECT_EQ(m.poses[1](0), 1.0);
  EXPECT_EQ(m.poses[1](1), -0.5);
  EXPECT_EQ(m.poses[1](2), 0.333251953125);
  EXPECT_EQ(m.poses[1](3), std::ldexp(1.0, -24));
}

// ---------------------------------------------------------------------------------------------
// Resampling

TEST(MotionResample, SameRateIsIdentityAndHalvingTakesEveryOtherFrame) {
  const Motion m = make_procedural_motion("running_on_spot", 60.0, 61);
  const Motion same = resample(m, 60.0);
  ASSERT_EQ(same.num_frames(), m.num_frames());
  for (std::size_t i = 0; i < m.num_frames(); ++i) {
    EXPECT_EQ(same.poses[i], m.poses[i]);
    EXPECT_EQ(same.trans[i], m.trans[i]);
  }
  const Motion half = resample(m, 30.0);
  ASSERT_EQ(half.num_frames(), 31u);
  for (std::size_t i = 0; i < half.num_frames(); ++i) EXPECT_EQ(half.poses[i], m.poses[2 * i]);
  // Upsampling a smooth motion lands close to the continuous curve.
  const Motion up = resample(m, 240.0), exact = make_procedural_motion("running_on_spot", 240.0, 241);
  ASSERT_EQ(up.num_frames(), 241u);
  double err = 0;
  for (std::size_t i = 0; i < up.num_frames(); ++i) err = std::max(err, (up.trans[i] - exact.trans[i]).norm());
  EXPECT_LT(err, 2e-3);
  EXPECT_THROW(resample(m, 0.0), Error);
}

TEST(MotionResample, SlerpTakesTheShortestArc) {
  // 170° and −170° about Z are 20° apart through 180°, not 340° through 0°.
  Pose a = Pose::Zero(), b = Pose::Zero();
  a.segment<3>(3) = Eigen::Vector3d(0, 0, 170 * kDeg);
  b.segment<3>(3) = Eigen::Vector3d(0, 0, -170 * kDeg);
  const Pose mid = slerp_pose(a, b, 0.5);
  EXPECT_NEAR(mid.segment<3>(3).norm(), 180 * kDeg, 1e-9);
  const Pose quarter = slerp_pose(a, b, 0.25);
  EXPECT_NEAR(quarter.segment<3>(3).norm(), 175 * kDeg, 1e-9);
  EXPECT_GT(quarter(5), 0.0);
  EXPECT_EQ(slerp_pose(a, b, 0.0).segment<3>(3), a.segment<3>(3));
  // Through resample: a 2-frame motion at 1 fps resampled to 2 fps.
  Motion m;
  m.fps = 1.0;
  m.poses = {a, b};
  m.trans = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 3)};
  const Motion r = resample(m, 2.0);
  ASSERT_EQ(r.num_frames(), 3u);
  EXPECT_NEAR(r.poses[1].segment<3>(3).norm(), 180 * kDeg, 1e-9);
  EXPECT_LT((r.trans[1] - Eigen::Vector3d(0.5, 1, 1.5)).norm(), 1e-15);
}

}  // namespace
}  // namespace sflsh::body
