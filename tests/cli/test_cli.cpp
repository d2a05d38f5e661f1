// The sflsh command line as users' scripts see it: the `motion export` contract, --help everywhere,
// and one-line errors with nothing written for every malformed input.
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "self_described.hpp"
#include "synthetic_body.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_reader.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <fstream>
#include <regex>

namespace sflsh {

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {

std::size_t count_lines(const std::string& text) {
  std::size_t n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = sflsh::testing::scratch_dir();
    body::save_body(dir_ / "synthetic.npz", sflsh::testing::synthetic_body(5, true));
  }
  std::string body_arg() const { return "--body " + (dir_ / "synthetic.npz").string(); }
  std::filesystem::path dir_;
};

}  // namespace

TEST_F(Cli, MotionExportWritesOneFramePerStepInVertexOrder) {
  const auto out = dir_ / "run";
  const auto r = run_sflsh("--quiet motion export " + body_arg() +
                               " --motion shake_hips --betas \"0.5 -1\" --frames 6 --out " + out.string(),
                           dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out / "body.pvd"));
  EXPECT_TRUE(std::filesystem::exists(out / "summary.json"));
  for (int t = 0; t < 6; ++t) EXPECT_TRUE(std::filesystem::exists(out / fmt::format("body_{:06d}.vtp", t))) << t;
  EXPECT_EQ(count_entries(out), 8u);  // 6 frames + pvd + summary: nothing else left behind

  // Points are the posed body in the model's vertex order.
  const body::BodyModel model = body::load_body(dir_ / "synthetic.npz");
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 6);
  const body::Poser poser(model, body::parse_betas("0.5 -1"));
  const sflsh::vtk::Points frame3 = sflsh::vtk::read_points(out / "body_000003.vtp");
  const body::RowMatrixX3d expected = poser.pose(motion.poses[3], motion.trans[3]);
  EXPECT_LT((frame3 - expected).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_THAT(sflsh::vtk::read_point_array_names(out / "body_000003.vtp"),
              ::testing::IsSupersetOf({"displacement", "skin_weights_argmax", "Normals"}));
  sflsh::testing::expect_self_described(out / "body_000003.vtp");

  std::ifstream pvd(out / "body.pvd");
  const std::string xml((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  const std::regex entry("timestep=\"([0-9.e-]+)\"[^>]*file=\"(body_[0-9]{6}\\.vtp)\"");
  std::vector<std::string> files;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), entry); it != std::sregex_iterator(); ++it)
    files.push_back((*it)[2]);
  ASSERT_EQ(files.size(), 6u);
  EXPECT_EQ(files.front(), "body_000000.vtp");
  EXPECT_EQ(files.back(), "body_000005.vtp");

  const nlohmann::json summary = read_json(out / "summary.json");
  EXPECT_EQ(summary["motion"]["frames"], 6);
  EXPECT_EQ(summary["motion"]["fps"], 60.0);
  EXPECT_EQ(summary["command"], "motion export");
  EXPECT_EQ(summary.at("timings").at("total_seconds"), summary.at("wall_time_s"));  // the older name, kept as an alias
}

TEST_F(Cli, MotionExportAsACompactXdmfSeriesHoldsTheSameFrames) {
  const std::string args = body_arg() + " --motion shake_hips --betas \"0.5 -1\" --frames 6 --out ";
  ASSERT_EQ(run_sflsh("-q motion export " + args + (dir_ / "vtk").string(), dir_).exit_code, 0);
  for (const char* precision : {"float32", "float64"}) {
    SCOPED_TRACE(precision);
    const auto out = dir_ / precision;
    const auto r = run_sflsh(
        fmt::format("-q motion export --format xdmf --precision {} {}{}", precision, args, out.string()), dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(count_entries(out), 3u);  // body.xmf, body.h5, summary.json
    const xdmf::SeriesReader series(out / "body.xmf");
    ASSERT_EQ(series.steps(), 6u);
    EXPECT_DOUBLE_EQ(series.time(5), 5.0 / 60.0);
    // The synthetic body is within a metre of the origin: Float32 rounds a coordinate by ≤ 2⁻²⁴ m ≈ 6e-8 m; Float64
    // keeps the .vtp frames' values exactly.
    const double tolerance = std::string(precision) == "float32" ? 1e-7 : 0.0;
    for (std::size_t t : {std::size_t{0}, std::size_t{3}, std::size_t{5}}) {
      const auto vtp = dir_ / "vtk" / fmt::format("body_{:06d}.vtp", t);
      EXPECT_LE((series.points(t) - sflsh::vtk::read_points(vtp)).cwiseAbs().maxCoeff(), tolerance) << t;
      for (const char* name : {"displacement", "velocity", "skin_weights_argmax", "Normals"}) {
        const Eigen::MatrixXd expected = sflsh::vtk::read_point_array(vtp, name);
        // Relative to the array's size (velocities reach m/s); Normals are Float32 in the .vtp frames as well.
        const double bound = std::string(name) == "Normals" ? 1e-6 : tolerance * (1.0 + expected.cwiseAbs().maxCoeff());
        EXPECT_LE((series.point_array(t, name) - expected).cwiseAbs().maxCoeff(), bound) << name << " at " << t;
      }
    }
    EXPECT_EQ(read_json(out / "summary.json")["series"], "body.xmf");
  }
  const auto lz4 = run_sflsh("motion export --format xdmf --compression lz4 " + args + (dir_ / "lz4").string(), dir_);
  EXPECT_EQ(lz4.exit_code, 1);
  EXPECT_THAT(lz4.err, HasSubstr("--compression lz4"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "lz4"));
}

TEST_F(Cli, AmassAtTheOutputRateIsUsedFrameForFrame) {
  body::Motion m = body::make_procedural_motion("running_on_spot", 60.0, 9);
  body::save_amass(dir_ / "clip.npz", m);
  const auto out = dir_ / "run";
  const auto r = run_sflsh("-q motion export " + body_arg() + " --motion " + (dir_ / "clip.npz").string() +
                               " --betas 0 --out " + out.string(),
                           dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_json(out / "summary.json")["motion"]["frames"], 9);
  const body::BodyModel model = body::load_body(dir_ / "synthetic.npz");
  const body::Poser poser(model, body::Betas::Zero());
  const body::Motion loaded = body::load_amass(dir_ / "clip.npz", 60.0);
  const body::RowMatrixX3d expected = poser.pose(m.poses[4], m.trans[4]) * loaded.world_from_body.transpose();
  EXPECT_LT((sflsh::vtk::read_points(out / "body_000004.vtp") - expected).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(Cli, HelpOnEverySubcommand) {
  for (const std::string cmd : {"", "body", "body info", "body generate", "body export", "body render", "motion",
                                "motion list", "motion export"}) {
    const auto r = run_sflsh(cmd + " --help", dir_);
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_THAT(r.out, HasSubstr("Usage")) << cmd;
  }
  const auto list = run_sflsh("motion list", dir_);
  EXPECT_EQ(list.exit_code, 0);
  for (const char* name :
       {"one_leg_jump", "running_on_spot", "shake_hips", "jiggle_on_toes", "shake_shoulders", "dance"})
    EXPECT_THAT(list.out, HasSubstr(name));
}

TEST_F(Cli, MalformedInputsFailWithOneLineAndWriteNothing) {
  std::ofstream(dir_ / "garbage.npz") << "not a zip";
  const auto out = dir_ / "never";
  struct Case {
    std::string args;
    std::string message;
  };
  const std::string b = body_arg();
  const std::string o = " --out " + out.string();
  const std::vector<Case> cases = {
      {"motion export " + b + " --motion nope --betas 0" + o, "motion 'nope'"},
      {"motion export " + b + " --motion shake_hips --betas \"1 x\"" + o, "'x' is not a number"},
      {"motion export " + b + " --motion shake_hips --subject NOBODY" + o, "unknown subject 'NOBODY'"},
      {"motion export " + b + " --motion shake_hips" + o, "one of --subject NAME or --betas"},
      {"motion export " + b + " --motion shake_hips --betas 0 --fps 0" + o, "--fps must be positive"},
      {"motion export --body " + (dir_ / "missing.npz").string() + " --motion shake_hips --betas 0" + o,
       "missing.npz: not found, expected a body model .npz file"},
      {"motion export --body " + (dir_ / "garbage.npz").string() + " --motion shake_hips --betas 0" + o,
       "garbage.npz: not a readable .npz"},
      {"motion export " + b + " --motion " + (dir_ / "garbage.npz").string() + " --betas 0" + o, "garbage.npz"},
  };
  for (const Case& c : cases) {
    const auto r = run_sflsh(c.args, dir_);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_THAT(r.err, HasSubstr(c.message)) << c.args;
    EXPECT_EQ(count_lines(r.err), 1u) << c.args << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args << ": output folder created";
  }
  // Both --subject and --betas: rejected by the parser.
  const auto both = run_sflsh("motion export " + b + " --motion shake_hips --betas 0 --subject DYNA_1" + o, dir_);
  EXPECT_NE(both.exit_code, 0);
  EXPECT_THAT(both.err, HasSubstr("excludes"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(Cli, BodyExportAndInfo) {
  const auto out = dir_ / "export";
  const auto r = run_sflsh("-q body export " + body_arg() + " --subject DYNA_2 --out " + out.string(), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(sflsh::vtk::read_points(out / "body.vtp").rows(), 24 * 5);
  EXPECT_EQ(read_json(out / "summary.json")["subject"], "DYNA_2");
  const auto info = run_sflsh("body info " + body_arg() + " --json", dir_);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto json = nlohmann::json::parse(info.out);
  EXPECT_EQ(json["vertices"], 120);
  EXPECT_EQ(json["joints"].size(), 24u);
  EXPECT_EQ(json["pose_correctives"], true);
}

}  // namespace sflsh
