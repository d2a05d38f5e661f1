// Material files: round trip, checks against the body, and one-line "<file>:<line>: …" errors naming the
// field for every kind of bad file.
#include "error_of.hpp"
#include "scratch_dir.hpp"
#include "test_fields_meshes.hpp"

#include <sflsh/material/control_points.hpp>
#include <sflsh/material/material_file.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <random>

namespace sflsh {

using namespace sflsh::material;
using sflsh::testing::error_of;
using ::testing::HasSubstr;

namespace {

// Line numbers of the base file matter: the error cases below name them.
const std::string kBase =
    "version = 1\n"                 // 1
    "body = \"sflsh-open-body\"\n"  // 2
    "subject = \"OPEN_TRAIN_1\"\n"  // 3
    "poisson = 0.2\n"               // 4
    "saturation = 4.0\n"            // 5
    "\n"                            // 6
    "[[control_point]]\n"           // 7
    "vertex = 10\n"                 // 8
    "thickness = 0.5\n"             // 9
    "young_tangent = 5000.0\n"      // 10
    "young_normal = 2000.0\n"       // 11
    "\n"                            // 12
    "[[control_point]]\n"           // 13
    "vertex = 20\n"                 // 14
    "position = [0.0, 1.0, 2.0]\n"  // 15
    "thickness = 0.3\n"             // 16
    "young_tangent = 800.0\n"       // 17
    "young_normal = 30000.0\n";     // 18

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(MaterialFile, ReadsTheDocumentedFormat) {
  const auto path = write_file(sflsh::testing::scratch_dir() / "m.toml", kBase);
  const MaterialFile m = load_material_file(path);
  EXPECT_EQ(m.body, "sflsh-open-body");
  EXPECT_EQ(m.subject, "OPEN_TRAIN_1");
  EXPECT_EQ(m.poisson, 0.2);
  EXPECT_EQ(m.saturation, 4.0);
  ASSERT_EQ(m.control_points.size(), 2u);
  EXPECT_EQ(m.vertices(), (std::vector<int>{10, 20}));
  EXPECT_FALSE(m.control_points[0].position.has_value());
  EXPECT_EQ(*m.control_points[1].position, Eigen::Vector3d(0.0, 1.0, 2.0));
  EXPECT_EQ(m.kappa()(1, kYoungNormal), 30000.0);
  EXPECT_EQ(m.control_points[1].line, 13);
  EXPECT_EQ(m.bounds.young_tangent.max, ParameterBounds{}.young_tangent.max);  // no [bounds]: the defaults
}

TEST(MaterialFile, RoundTripsExactly) {
  const auto mesh = sflsh::testing::body_skin();
  MaterialFile m;
  m.body = "sflsh-open-body";
  m.subject = "TEST \"quoted\" subject";  // exercises string escaping
  m.poisson = 0.25;
  m.saturation = 3.5;
  m.bounds.thickness = {0.05, 0.95};
  m.bounds.young_normal = {100.0, 2e5};
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const int v : place_control_points(mesh.V, mesh.F, 24)) {
    MaterialControlPoint p;
    p.vertex = v;
    if (v % 2 == 0) p.position = mesh.V.row(v).transpose();
    p.kappa = {0.05 + 0.9 * unit(rng), 500.0 * std::pow(100.0, unit(rng)), 100.0 * std::pow(2000.0, unit(rng))};
    m.control_points.push_back(p);
  }
  const auto path = sflsh::testing::scratch_dir() / "material.toml";
  save_material_file(path, m, "written by the test\nsecond line");
  const MaterialFile back = load_material_file(path);
  EXPECT_EQ(back.body, m.body);
  EXPECT_EQ(back.subject, m.subject);
  EXPECT_EQ(back.poisson, m.poisson);
  EXPECT_EQ(back.saturation, m.saturation);
  EXPECT_EQ(back.bounds.minimum(), m.bounds.minimum());
  EXPECT_EQ(back.bounds.maximum(), m.bounds.maximum());
  EXPECT_EQ(back.vertices(), m.vertices());
  EXPECT_EQ(back.kappa(), m.kappa());  // shortest round-trip decimals: bit-exact
  for (std::size_t i = 0; i < m.control_points.size(); ++i)
    EXPECT_EQ(back.control_points[i].position, m.control_points[i].position);
  EXPECT_NO_THROW(check_against_body(back, mesh.V, 0.0, path.string()));  // exact positions: zero tolerance
}

TEST(MaterialFile, ChecksAgainstTheBody) {
  const auto path = write_file(sflsh::testing::scratch_dir() / "m.toml", kBase);
  const MaterialFile m = load_material_file(path);
  RowMatrixX3d V = RowMatrixX3d::Zero(30, 3);
  V.row(20) << 0.0, 1.0, 2.0;
  EXPECT_NO_THROW(check_against_body(m, V, 1e-6, path.string()));
  V(20, 2) += 0.001;  // 1 mm off: another body
  EXPECT_THAT(error_of([&] { check_against_body(m, V, 1e-6, path.string()); }),
              HasSubstr(path.string() + ":13: control_point #1 'position' is 0.001 m from vertex 20"));
  EXPECT_THAT(error_of([&] { check_against_body(m, V.topRows(15), 1e-6, path.string()); }),
              HasSubstr(path.string() + ":13: control_point #1 'vertex' = 20 is outside the body's 15 vertices"));
}

TEST(MaterialFile, BadFilesGiveOneLineErrorsWithFileLineAndField) {
  const auto dir = sflsh::testing::scratch_dir();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {replaced(kBase, "body = \"sflsh-open-body\"\n", ""), "missing key 'body'"},
      {replaced(kBase, "body = \"sflsh-open-body\"", "body = 3"), ":2: 'body' must be a string"},
      {replaced(kBase, "poisson = 0.2", "poisson = \"x\""), ":4: 'poisson' must be a number"},
      {replaced(kBase, "poisson = 0.2", "poisson = 0.5"), ":4: 'poisson' = 0.5 is outside (-1, 0.5)"},
      {replaced(kBase, "saturation = 4.0", "saturation = 0"), ":5: saturation: 0 is outside (0, 100]"},
      {replaced(kBase, "version = 1", "version = 2"), ":1: 'version' must be the integer 1"},
      {replaced(kBase, "poisson = 0.2", "poisson = = 0.2"), ":4:"},  // TOML syntax
      {replaced(kBase, "subject", "colour = 1\nsubject"), ":3: unknown key 'colour'"},
      {replaced(kBase, "vertex = 10", "vertex = 10.0"), ":8: 'vertex' in control_point #0 must be an integer"},
      {replaced(kBase, "vertex = 10", "vertex = -1"), ":8: 'vertex' in control_point #0 = -1 must be a vertex index"},
      {replaced(kBase, "vertex = 20", "vertex = 10"), ":14: 'vertex' in control_point #1 repeats vertex 10"},
      {replaced(kBase, "thickness = 0.5", "thickness = 0.95"),
       ":9: 'thickness' in control_point #0 = 0.95 is outside the bounds [0.1, 0.9]"},
      {replaced(kBase, "young_normal = 30000.0", "young_normal = 60000.0"),
       ":18: 'young_normal' in control_point #1 = 60000 is outside the bounds [500, 50000] Pa"},
      {replaced(kBase, "young_tangent = 800.0", "young_tangent = true"),
       ":17: 'young_tangent' in control_point #1 must be a number"},
      {replaced(kBase, "young_normal = 2000.0\n", ""), ":7: missing key 'young_normal' in control_point #0"},
      {replaced(kBase, "thickness = 0.5", "thickness = 0.5\nstiffness = 3"),
       ":10: unknown key 'stiffness' in control_point #0"},
      {replaced(kBase, "position = [0.0, 1.0, 2.0]", "position = [0.0, 1.0]"),
       ":15: 'position' in control_point #1 must be an array of 3 numbers"},
      {replaced(kBase, "saturation = 4.0\n", "saturation = 4.0\n[bounds]\nthickness = [0.5, 0.2]\n"),
       ":7: parameter bounds: thickness = [0.5, 0.2]"},
      {replaced(kBase, "saturation = 4.0\n", "saturation = 4.0\n[bounds]\nthickness = [0.2, 0.4]\n"),
       ":11: 'thickness' in control_point #0 = 0.5 is outside the bounds [0.2, 0.4]"},  // bounds apply to points
      {kBase.substr(0, kBase.find("[[control_point]]")), "no [[control_point]] tables"},
      {replaced(kBase.substr(0, kBase.find("[[control_point]]")), "saturation = 4.0",
                "saturation = 4.0\ncontrol_point = 3"),
       ":6: 'control_point' must be a non-empty array of tables"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto path = write_file(dir / fmt::format("bad{}.toml", k), cases[k].first);
    const std::string message = error_of([&] { load_material_file(path); });
    EXPECT_THAT(message, HasSubstr(cases[k].second)) << "case " << k << ":\n" << cases[k].first;
    EXPECT_THAT(message, HasSubstr(path.string())) << "case " << k;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line, case " << k;
  }
  EXPECT_THAT(error_of([&] { load_material_file(dir / "absent.toml"); }),
              HasSubstr("absent.toml: not found, expected a material TOML file"));
}

TEST(MaterialFile, RefusesToWriteAnInvalidFile) {
  MaterialFile m;
  m.body = "b";
  m.subject = "s";
  m.control_points = {{7, std::nullopt, {0.5, 1000.0, 1000.0}, 0}, {7, std::nullopt, {0.5, 1000.0, 1000.0}, 0}};
  const auto path = sflsh::testing::scratch_dir() / "never.toml";
  EXPECT_THAT(error_of([&] { save_material_file(path, m); }), HasSubstr("control_point #1 repeats vertex 7"));
  EXPECT_FALSE(std::filesystem::exists(path));
  m.control_points.pop_back();
  m.control_points[0].kappa.young_tangent = 1e9;
  EXPECT_THAT(error_of([&] { save_material_file(path, m); }), HasSubstr("young_tangent = 1000000000 is outside"));
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace sflsh
