// The CLI on bad text input and runaway requests (issue 23): every refusal is one line naming the file and
// field, exits 1 and writes nothing; runs above the work limits need --allow-long.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>

namespace sflsh {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;
using ::testing::Not;

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

/// One tetrahedron with point groups "base" (nodes 1–3) and "tip" (node 4), gmsh 2.2.
std::string tet_msh(const std::string& node_count = "4") {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
         "$PhysicalNames\n3\n0 1 \"base\"\n0 2 \"tip\"\n3 3 \"volume\"\n$EndPhysicalNames\n"
         "$Nodes\n" +
         node_count +
         "\n1 0 0 0\n2 0.1 0 0\n3 0 0.1 0\n4 0 0 0.1\n$EndNodes\n"
         "$Elements\n5\n1 15 2 1 1 1\n2 15 2 1 2 2\n3 15 2 1 3 3\n4 15 2 2 4 4\n5 4 2 3 1 1 2 3 4\n$EndElements\n";
}

std::string tet_problem(const std::string& young = "5000.0", const std::string& duration = "0.1",
                        const std::string& step = "0.01") {
  return "mesh = \"tet.msh\"\n"  // 1
         "density = 1000.0\n"    // 2
         "[material]\n"          // 3
         "young_tangent = " +
         young +
         "\n"                       // 4
         "young_normal = 2000.0\n"  // 5
         "[[fix]]\n"                // 6
         "group = \"base\"\n"       // 7
         "components = \"xyz\"\n"   // 8
         "[time]\n"                 // 9
         "duration = " +
         duration +
         "\n"  // 10
         "step = " +
         step +
         "\n"                  // 11
         "[record]\n"          // 12
         "group = \"tip\"\n";  // 13
}

struct Refusal {
  std::string args;
  std::vector<std::string> expected;
};

/// Refused with exit code 1 and one line holding every expected part; nothing is written into the output folder.
void expect_refused(const Refusal& c, const fs::path& dir, const fs::path& out) {
  fs::remove_all(out);
  const auto r = run_sflsh(c.args + " --out " + out.string(), dir);
  EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.err;
  for (const std::string& e : c.expected) EXPECT_THAT(r.err, HasSubstr(e)) << c.args;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << "\n" << r.err;
  EXPECT_EQ(sflsh::testing::count_entries(out), 0u) << c.args << ": wrote into the output folder";
}

TEST(CliLimits, VerifyRefusesRunawayStepsBadMaterialAndLyingMeshHeaders) {
  const auto dir = testing::scratch_dir();
  write(dir / "tet.msh", tet_msh());
  const auto out = dir / "out";
  const std::string problem = (dir / "p.toml").string();
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {tet_problem("5000.0", "1e9", "0.01"),
       {"p.toml: time.duration / time.step (and record.every): 1e+11 solver steps exceed the limit of 1e+06",
        "pass --allow-long to run it anyway"}},
      {tet_problem("5000.0", "1.0", "1e-12"), {"1e+12 solver steps exceed the limit", "--allow-long"}},
      {tet_problem("1e30"), {"p.toml:4: material.young_tangent: 1e+30 Pa is outside [1, 1e+09] Pa"}},
      {tet_problem() + "[solver]\nhessian = \"exact\"\n", {}},  // valid: runs (checked below)
  };
  for (const auto& [text, expected] : cases) {
    write(problem, text);
    if (expected.empty()) {
      const auto r = run_sflsh("-q verify " + problem + " --no-vtk --out " + out.string(), dir);
      EXPECT_EQ(r.exit_code, 0) << r.err;
      fs::remove_all(out);
      continue;
    }
    expect_refused({"verify " + problem, expected}, dir, out);
  }
  // A header announcing two billion nodes: refused at once, no allocation for them.
  write(problem, tet_problem());
  write(dir / "tet.msh", tet_msh("2000000000"));
  expect_refused(
      {"verify " + problem,
       {"p.toml:1: mesh: ", "tet.msh:11: $Nodes: number of nodes = 2000000000 is more than the rest of the file"}},
      dir, out);
  fs::create_directories(dir / "tet_dir.msh");
  write(problem, std::regex_replace(tet_problem(), std::regex("tet.msh"), "tet_dir.msh"));
  expect_refused({"verify " + problem, {"p.toml:1: mesh: ", "tet_dir.msh: is a directory, expected a gmsh .msh file"}},
                 dir, out);
}

TEST(CliLimits, FileOptionsThatAreDirectoriesSaySo) {
  const auto dir = testing::scratch_dir();
  fs::create_directories(dir / "a_directory.toml");
  const std::string d = (dir / "a_directory.toml").string();
  const auto out = dir / "out";
  const std::string body = "simulate --solver reduced --subject OPEN_TRAIN_1 --motion dance --frames 2 --mesh coarse";
  for (const Refusal& c : std::vector<Refusal>{
           {body + " --material " + d, {d + ": is a directory, expected a material TOML file"}},
           {"simulate --scene " + d, {d + ": is a directory, expected a scene TOML file"}},
           {body + " --body " + d, {d + ": is a directory, expected a body model .npz file"}},
           {"simulate --solver reduced --subject OPEN_TRAIN_1 --frames 2 --motion " + d,
            {d + ": is a directory, expected an AMASS motion .npz file"}},
           {"verify " + d, {d + ": is a directory, expected a verify problem TOML file"}},
           {"material show --material " + d, {d + ": is a directory, expected a material TOML file"}},
       })
    expect_refused(c, dir, out);
}

TEST(CliLimits, SimulateRefusesRunawayFramesAndCrowdsUnlessAllowed) {
  const auto dir = testing::scratch_dir();
  const auto out = dir / "out";
  expect_refused({"simulate --solver reduced --subject OPEN_TRAIN_1 --motion dance --frames 100000000 --mesh coarse",
                  {"--frames × --substeps (or the motion's length): 1e+08 solver steps exceed the limit of 1e+06",
                   "--allow-long"}},
                 dir, out);
  const auto crowd = write(dir / "crowd.toml",
                           "[scene]\nfps = 30\nduration = 2.0\n[effects]\ninertia = true\n[crowd]\ncount = 100000\n");
  expect_refused({"simulate --scene " + crowd.string(),
                  {"crowd.toml: [scene] duration", "1e+05 bodies exceed the limit of 100", "--allow-long"}},
                 dir, out);
}

TEST(CliLimits, SkinnedBodyFarIntoItsMotionRunsInConstantMemoryAndBeyondTheBoundIsRefused) {
  const auto dir = testing::scratch_dir();
  const auto out = dir / "out";
  const std::string scene =
      "[scene]\nfps = 30\nframes = 2\n[[body]]\nmotion = \"dance\"\nsolver = \"skinned\"\nmotion_offset = ";
  const auto far = write(dir / "far.toml", scene + "3600.0\n");
  const auto r = run_sflsh("-q simulate --scene " + far.string() + " --no-output --out " + out.string(), dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  fs::remove_all(out);
  const auto beyond = write(dir / "beyond.toml", scene + "1e9\n");
  expect_refused({"simulate --scene " + beyond.string(),
                  {"beyond.toml:7: motion_offset in body #0: 1e+09 s is outside [0, 3600] s"}},
                 dir, out);
}

TEST(CliLimits, MaterialForAnotherBodyIsRefusedBeforeMeshing) {
  const auto dir = testing::scratch_dir();
  const auto m = write(dir / "m.toml",
                       "body = 'smpl'\nsubject = 'x'\npoisson = 0.2\nsaturation = 4.0\n[[control_point]]\nvertex = 7\n"
                       "thickness = 0.5\nyoung_tangent = 5000.0\nyoung_normal = 2000.0\n");
  expect_refused({fmt::format("material show --material {} --mesher layered --size coarse --cache {}", m.string(),
                              SFLSH_TEST_CACHE),
                  {m.string() + ": body: the material is for body 'smpl', but the run uses body 'open_body'"}},
                 dir, dir / "out");
}

TEST(CliLimits, EchoedInputIsCutAt300Characters) {
  const auto dir = testing::scratch_dir();
  write(dir / "tet.msh", tet_msh());
  // A 200 000-character drive expression that muparser refuses: the message keeps its first 300 characters.
  std::string expression = "t";
  while (expression.size() < 200'000) expression += "+t";
  expression += "+(";
  const auto problem = write(dir / "p.toml", tet_problem() +
                                                 "[[drive]]\ngroup = \"tip\"\ncomponent = \"x\"\n"
                                                 "expression = \"" +
                                                 expression + "\"\n");
  const auto r = run_sflsh("-q verify " + problem.string() + " --no-vtk --out " + (dir / "out").string(), dir);
  EXPECT_EQ(r.exit_code, 1) << r.err.substr(0, 2000);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
  EXPECT_THAT(r.err,
              HasSubstr("'" + expression.substr(0, 300) + "… (" + std::to_string(expression.size()) + " characters)'"));
  EXPECT_LT(r.err.size(), 1500u) << r.err.substr(0, 2000);

  // A name given on the command line: cut the same way.
  const std::string subject(1000, 'x');
  const auto s = run_sflsh("-q body info --subject " + subject, dir);
  EXPECT_NE(s.exit_code, 0);
  EXPECT_THAT(s.err, HasSubstr("'" + subject.substr(0, 300) + "… (1000 characters)'")) << s.err;
  EXPECT_THAT(s.err, Not(HasSubstr(subject.substr(0, 301))));
}

}  // namespace

// A material at the thickness bound `material show` writes (0.9) gets a valid layer: the layered coarse mesh inverts
// tets for TEST_3 there (its one prism layer twists where the columns converge), and the layered mesh with more prism
// layers replaces it (docs/meshing.md, "Every mesher at every thickness"); this run used to fail.
TEST(CliLimits, MaterialAtTheThicknessBoundGetsAValidLayer) {
  const fs::path dir = sflsh::testing::scratch_dir();
  auto r = run_sflsh(fmt::format("-q material show --subject TEST_3 --control-points 6 --mesher layered --mesh coarse "
                                 "--cache {} --out {}",
                                 SFLSH_TEST_CACHE, (dir / "show").string()),
                     dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const long template_tets = read_json(dir / "show" / "summary.json")["tets"].get<long>();
  std::string text = sflsh::testing::text_of(dir / "show" / "material.toml");
  const std::size_t points = text.find("[[control_point]]");
  ASSERT_NE(points, std::string::npos);
  text = text.substr(0, points) +
         std::regex_replace(text.substr(points), std::regex(R"(\nthickness = [-0-9.e]+)"), "\nthickness = 0.9");
  const fs::path thick = dir / "thick.toml";
  std::ofstream(thick) << text;
  r = run_sflsh(fmt::format("-q material show --subject TEST_3 --material {} --mesher layered --mesh coarse --cache {} "
                            "--out {}",
                            thick.string(), SFLSH_TEST_CACHE, (dir / "thick").string()),
                dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json summary = read_json(dir / "thick" / "summary.json");
  EXPECT_GT(summary["tets"].get<long>(), template_tets) << "more prism layers than the coarse preset's one";
  const auto h = sflsh::vtk::read_point_array(dir / "thick" / "layer.vtu", "thickness_fraction");
  EXPECT_NEAR(h.maxCoeff(), 0.9, 1e-6);
}

}  // namespace sflsh
