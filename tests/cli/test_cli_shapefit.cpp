// `sflsh shapefit`: a shape model fitted to material files (SFLSH eqs. 1, 4, 5), taken by `material show`, and
// one line for each kind of bad input with nothing written.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <fstream>
#include <regex>

namespace sflsh {

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using sflsh::testing::text_of;
using ::testing::HasSubstr;

namespace {

std::string layered_coarse_args() { return fmt::format("--mesher layered --mesh coarse --cache {}", SFLSH_TEST_CACHE); }

/// The control vertices of a 4-point material of the open body (as `material show` places them).
std::vector<int> control_vertices(const std::filesystem::path& dir) {
  const auto out = dir / "show";
  const auto result = run_sflsh(
      fmt::format("-q material show --control-points 4 {} --out {}", layered_coarse_args(), out.string()), dir);
  EXPECT_EQ(result.exit_code, 0) << result.err;
  const std::string text = text_of(out / "material.toml");
  std::vector<int> vertices;
  const std::regex vertex_line(R"(\nvertex = (\d+))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), vertex_line); it != std::sregex_iterator(); ++it)
    vertices.push_back(std::stoi((*it)[1]));
  EXPECT_EQ(vertices.size(), 4u);
  return vertices;
}

/// A material file of subject `name` with shape β_1 = a, β_2 = b (the rest 0) and κ linear in them, or with
/// `override_line` replacing the first control point's thickness line.
void write_material(const std::filesystem::path& path, const std::string& name, double a, double b,
                    const std::vector<int>& vertices, bool with_betas = true, const std::string& thickness_line = "") {
  std::ofstream out(path);
  out << "body = 'open_body'\nsubject = '" << name << "'\n";
  if (with_betas) out << fmt::format("betas = [{}, {}, 0, 0, 0, 0, 0, 0, 0, 0]\n", a, b);
  out << "poisson = 0.2\nsaturation = 4.0\n[bounds]\nthickness = [0.1, 0.9]\nyoung_tangent = [500.0, 50000.0]\n"
         "young_normal = [500.0, 50000.0]\n";
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    out << "[[control_point]]\nvertex = " << vertices[i] << "\n";
    if (i == 0 && !thickness_line.empty())
      out << thickness_line << "\n";
    else
      out << fmt::format("thickness = {}\n", 0.5 + 0.04 * a - 0.02 * static_cast<double>(i) * b);
    out << fmt::format("young_tangent = {}\nyoung_normal = {}\n", 8000.0 * (1.0 + 0.1 * b), 4000.0 * (1.0 - 0.05 * a));
  }
}

const double kShapes[][2] = {{-1.5, 0.3}, {-0.7, -1.1}, {0.0, 0.8}, {0.6, -0.4}, {1.2, 1.5}, {1.9, -0.9}};

}  // namespace

TEST(CliShapefit, FitsAShapeModelThatMaterialShowTakes) {
  const auto dir = sflsh::testing::scratch_dir();
  const std::vector<int> vertices = control_vertices(dir);
  ASSERT_EQ(vertices.size(), 4u);
  const auto materials = dir / "materials";
  std::filesystem::create_directories(materials);
  for (int s = 0; s < 6; ++s)
    write_material(materials / fmt::format("s{}.toml", s), fmt::format("S{}", s), kShapes[s][0], kShapes[s][1],
                   vertices);
  const auto out = dir / "fit";
  auto result = run_sflsh(fmt::format("-q shapefit --materials {} --regularizer local {} --out {}", materials.string(),
                                      layered_coarse_args(), out.string()),
                          dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* file :
       {"shape_model.toml", "cross_validation.csv", "lambda_sweep.csv", "lambda_sweep.png", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / file)) << file;
  const nlohmann::json summary = read_json(out / "summary.json");
  EXPECT_EQ(summary["regularizer"], "local");
  EXPECT_EQ(summary["lambda_rule"], "one-se");
  EXPECT_GT(summary["lambda"].get<double>(), 0.0);
  EXPECT_EQ(summary["control_points"], 4);
  const std::size_t lambdas = summary["cv_errors"].size();
  EXPECT_GE(lambdas, 25u);  // the auto grid: half decades 1e-6 … 1e6, possibly extended
  // cross_validation.csv: one row per λ and left-out subject.
  const std::string cv = text_of(out / "cross_validation.csv");
  EXPECT_EQ(cv.rfind("lambda,left_out,rms_error\n", 0), 0u);
  EXPECT_EQ(static_cast<std::size_t>(std::count(cv.begin(), cv.end(), '\n')), 1 + 6 * lambdas);
  // κ is linear in β here, so the fit reproduces the train subjects closely (normalized units).
  for (const auto& [subject, error] : summary["train_rms_error"].items())
    EXPECT_LT(error.get<double>(), 0.01) << subject;
  const std::string model = text_of(out / "shape_model.toml");
  EXPECT_THAT(model, HasSubstr("regularizer = 'local'"));
  EXPECT_THAT(model, HasSubstr("mesh = 'coarse'"));

  // `material show --shape-model` takes it (same region and mesh) for any subject.
  result = run_sflsh(fmt::format("-q material show --subject OPEN_TEST_1 --shape-model {} {} --out {}",
                                 (out / "shape_model.toml").string(), layered_coarse_args(), (dir / "shown").string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_THAT(text_of(dir / "shown" / "material.toml"), HasSubstr("betas = ["));

  // Comma-separated files, no regularizer: λ = 0 and one row of the sweep.
  std::string list;
  for (int s = 0; s < 6; ++s) list += (s ? "," : "") + (materials / fmt::format("s{}.toml", s)).string();
  result = run_sflsh(fmt::format("-q shapefit --materials {} --regularizer none {} --out {}", list,
                                 layered_coarse_args(), (dir / "none").string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(read_json(dir / "none" / "summary.json")["lambda"], 0.0);
  EXPECT_EQ(read_json(dir / "none" / "summary.json")["cv_errors"].size(), 1u);
}

TEST(CliShapefit, BadInputGivesOneLineNamingTheFileAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  const std::vector<int> vertices = {100, 200, 300};
  auto good = [&](int s) {
    const auto path = dir / fmt::format("good{}.toml", s);
    write_material(path, fmt::format("S{}", s), kShapes[s][0], kShapes[s][1], vertices);
    return path.string();
  };
  const std::string a = good(0), b = good(1);
  const auto moved = dir / "moved.toml";
  write_material(moved, "M", 0.3, 0.2, {100, 201, 300});
  const auto unknown = dir / "unknown.toml";
  write_material(unknown, "NOBODY", 0.3, 0.2, vertices, false);
  const auto nan = dir / "nan.toml";
  write_material(nan, "N", 0.3, 0.2, vertices, true, "thickness = nan");
  const auto outside = dir / "outside.toml";
  write_material(outside, "O", 0.3, 0.2, vertices, true, "thickness = 0.95");
  struct Case {
    std::string materials, extra, expected_file, expected_field;
  };
  const std::vector<Case> cases = {
      {a, "", "--materials", "2 or more"},
      {a + "," + moved.string(), "", moved.string(), "vertex"},
      {a + "," + unknown.string(), "", unknown.string(), "subject"},
      {a + "," + nan.string(), "", nan.string(), "thickness"},
      {a + "," + outside.string(), "", outside.string(), "thickness"},
      {a + "," + b, "--lambdas 0.1,abc", "--lambdas", "abc"},
      {a + "," + (dir / "missing.toml").string(), "", (dir / "missing.toml").string(), ""},
  };
  for (const Case& c : cases) {
    const auto out = dir / "out";
    const auto result = run_sflsh(fmt::format("shapefit --materials {} --regularizer l2 {} {} --out {}", c.materials,
                                              c.extra, layered_coarse_args(), out.string()),
                                  dir);
    EXPECT_NE(result.exit_code, 0) << c.materials;
    EXPECT_THAT(result.err, HasSubstr(c.expected_file));
    EXPECT_THAT(result.err, HasSubstr(c.expected_field));
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_EQ(count_entries(out), 0u) << c.materials;
  }
}

}  // namespace sflsh
