// sflsh simulate --scene: the contract (summary.json with "effects") and bad input (one line, nothing written).
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace sflsh {
namespace {

TEST(CliScene, SkinningOnlySceneWritesSeriesAndEffects) {
  const auto dir = testing::scratch_dir();
  const std::string scene = std::string(SFLSH_DATA_DIR) + "/scenes/skinning_only.toml";
  const auto r = testing::run_sflsh("simulate --scene " + scene + " --frames 3 --out " + (dir / "out").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "out" / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  ASSERT_TRUE(s.contains("effects"));
  ASSERT_EQ(s["effects"].size(), 1u);
  EXPECT_EQ(s["effects"][0]["name"], "skinning");
  EXPECT_TRUE(s["effects"][0].contains("seconds"));
  EXPECT_EQ(s["scene"]["frames"], 3);
  for (const char* f : {"dancer.pvd", "runner.pvd", "dancer_000002.vtp", "runner_000002.vtp"})
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / f)) << f;
  // One collection opens the scene: both bodies at each of the 3 frames; no σ maps without a soft body.
  std::ifstream pvd(dir / "out" / "scene.pvd");
  const std::string xml((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  for (const char* f :
       {R"(part="0" name="dancer" file="dancer_000000.vtp")", R"(part="1" name="runner" file="runner_000002.vtp")"})
    EXPECT_NE(xml.find(f), std::string::npos) << f;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "scene_dynamics.pvd"));
  EXPECT_EQ(s["output"]["collections"], nlohmann::json::array({"scene.pvd"}));
}

TEST(CliScene, BadSceneIsOneLineAndWritesNothing) {
  const auto dir = testing::scratch_dir();
  std::ofstream(dir / "bad.toml") << "[scene]\nfps = 30\n[[body]]\nmotion = \"rest\"\nhandels = 30\n";
  const auto r =
      testing::run_sflsh("simulate --scene " + (dir / "bad.toml").string() + " --out " + (dir / "out").string(), dir);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("bad.toml:5: unknown key 'handels' in body #0"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  const auto m = testing::run_sflsh("simulate --out " + (dir / "out").string(), dir);
  EXPECT_NE(m.exit_code, 0);
  EXPECT_NE(m.err.find("--motion is required (or give a scene with --scene FILE)"), std::string::npos) << m.err;
}

TEST(CliScene, EveryWritesTheChosenFramesAndBadValuesWriteNothing) {
  const auto dir = testing::scratch_dir();
  const std::string scene = std::string(SFLSH_DATA_DIR) + "/scenes/skinning_only.toml";
  const auto r =
      testing::run_sflsh("simulate --scene " + scene + " --frames 6 --every 4 --out " + (dir / "out").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int f = 0; f < 6; ++f) {
    const bool written = f == 0 || f == 4 || f == 5;
    EXPECT_EQ(std::filesystem::exists(dir / "out" / ("dancer_00000" + std::to_string(f) + ".vtp")), written) << f;
  }
  std::ifstream in(dir / "out" / "summary.json");
  EXPECT_EQ(nlohmann::json::parse(in)["output"]["every"], 4);

  const auto zero =
      testing::run_sflsh("simulate --scene " + scene + " --every 0 --out " + (dir / "zero").string(), dir);
  EXPECT_NE(zero.exit_code, 0);
  EXPECT_NE(zero.err.find("--every must be at least 1, got 0"), std::string::npos) << zero.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "zero"));
  std::ofstream(dir / "bad.toml") << "[scene]\nfps = 30\n[output]\nevery = -2\n[[body]]\nmotion = \"rest\"\n";
  const auto bad =
      testing::run_sflsh("simulate --scene " + (dir / "bad.toml").string() + " --out " + (dir / "bad").string(), dir);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("bad.toml:4: 'every' in [output] = -2 must be an integer in [1, 10⁶]"), std::string::npos)
      << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
}

}  // namespace
}  // namespace sflsh
