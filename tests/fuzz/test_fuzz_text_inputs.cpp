// Fuzzing the command line with mutated text inputs (label `fuzz`): material, scene and shape-model TOML,
// OBJ obstacles, gmsh .msh + verify TOML. Besides the seeded random mutations, each kind runs the values a
// user reported as crashing or running away (targeted cases), so they stay fixed.
#include "fuzz_harness.hpp"
#include "mutators.hpp"
#include "scratch_dir.hpp"

#include <sflsh/fullspace/msh_reader.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>

namespace sflsh::testing::fuzz {
namespace {

namespace fs = std::filesystem;

const std::string kObstacle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/// Skinning only (no effect asked for): bodies, a crowd and every object shape, 3 frames.
const std::string kScene = R"toml([scene]
name = "fuzz"
fps = 30
duration = 0.1

[effects]
inertia = false

[[body]]
name = "a"
subject = "OPEN_TRAIN_1"
motion = "dance"
motion_offset = 0.5
solver = "reduced"
placement = { position = [1.0, 0.0, 0.0], yaw = 30.0 }

[[object]]
name = "floor"
shape = "plane"
normal = [0.0, 1.0, 0.0]
position = [0.0, -1.2, 0.0]

[[object]]
name = "ball"
shape = "sphere"
radius = 0.1
motion = "prescribed"
keyframes = [ { t = 0.0, position = [0.0, 0.5, 0.5] }, { t = 0.1, position = [0.0, 0.5, 0.4] } ]

[[object]]
name = "crate"
shape = "box"
half_extents = [0.1, 0.1, 0.1]
position = [1.0, 0.0, 1.0]

[[object]]
name = "pole"
shape = "capsule"
radius = 0.05
length = 0.5
position = [-1.0, 0.0, 1.0]

[[object]]
name = "rock"
shape = "mesh"
file = "obstacle.obj"
scale = 0.2
position = [0.0, 0.0, 2.0]

[crowd]
count = 2
seed = 3
motion = "dance"
max_offset = 1.0
spacing = 1.6
columns = 2
shape_model = "shape_model.toml"
solver = "reduced"
mesh = "coarse"
)toml";

const std::string kVerify = R"toml(mesh = "bar.msh"
density = 1000.0

[material]
young_tangent = 5000.0
young_normal = 2000.0
poisson = 0.2
saturation = 4.0
normal = [0.0, 0.0, 1.0]

[[fix]]
group = "xmin"
components = "xyz"

[[drive]]
group = "xmax"
component = "y"
expression = "0.01*sin(2*pi*2*t)"

[time]
duration = 0.05
step = 0.0083333333333333333
integrator = "backward_euler"

[record]
group = "xmax"
every = 3
)toml";

void write_scene_inputs(const fs::path& dir) {
  write_text(dir / "scene.toml", kScene);
  write_text(dir / "obstacle.obj", kObstacle);
  fs::copy_file(fs::path(SFLSH_DATA_DIR) / "shape_models" / "default.toml", dir / "shape_model.toml",
                fs::copy_options::overwrite_existing);
}

void write_verify_inputs(const fs::path& dir) {
  const fullspace::MshMesh mesh = fullspace::box_tet_mesh(Eigen::Vector3d(0.1, 0.02, 0.02), {4, 1, 1});
  fullspace::write_msh(dir / "bar.msh", mesh.nodes, mesh.tets, mesh.node_groups, fullspace::MshVersion::v41);
  write_text(dir / "problem.toml", kVerify);
}

/// A text kind: the base text, the command, the random mutator, and targeted (key, value) cases.
struct TextKind {
  std::string name;
  std::string file_name;
  std::function<std::string(const fs::path& workdir)> base;  ///< the valid text of the input
  std::function<void(const fs::path& workdir)> prepare;      ///< the other files of the run
  std::function<std::string(const fs::path& input, const fs::path& out)> arguments;
  bool toml = true;                                           ///< TOML mutations, else token mutations
  std::vector<std::pair<std::string, std::string>> targeted;  ///< key → value (value "<delete>" deletes the line)
};

std::string without_line_of(const std::string& text, const std::string& key) {
  std::string out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key + " =", 0) == 0 || line.rfind(key + "=", 0) == 0) continue;
    out += line + "\n";
  }
  return out;
}

void fuzz_text_kind(const TextKind& kind, std::uint64_t seed) {
  const fs::path root = scratch_dir();
  Tally tally;
  const int random_cases = cases_per_kind();
  const int total = random_cases + static_cast<int>(kind.targeted.size()) + 1;
  for (int k = 0; k < total; ++k) {
    const fs::path workdir = root / fmt::format("case{:03d}", k);
    fs::create_directories(workdir);
    if (kind.prepare) kind.prepare(workdir);
    const fs::path input = workdir / kind.file_name;
    const std::string base = kind.base(workdir);
    Case c;
    c.kind = kind.name;
    c.input = input;
    c.out = workdir / "run";
    if (k < random_cases) {
      Random random(seed * 1000003ull + static_cast<std::uint64_t>(k));
      std::string what;
      write_text(input, kind.toml ? mutate_toml(base, random, what) : mutate_tokens(base, random, what));
      c.mutation = fmt::format("seed {} case {}: {}", seed, k, what);
    } else if (k < total - 1) {
      const auto& [key, value] = kind.targeted[static_cast<std::size_t>(k - random_cases)];
      const std::string text = value == "<delete>" ? without_line_of(base, key) : replace_toml_value(base, key, value);
      ASSERT_FALSE(text.empty()) << kind.name << ": targeted key '" << key << "' not in the base input";
      write_text(input, text);
      c.mutation = "targeted: " + key + (value == "<delete>" ? " deleted" : " = " + value);
    } else {
      fs::remove(input);
      fs::create_directories(input);
      c.mutation = "a folder in place of the file";
    }
    c.arguments = kind.arguments(input, c.out);
    tally.add(run_case(c, workdir));
  }
  std::cout << tally.cases() << tally.table();
  for (const Outcome& o : tally.failures())
    ADD_FAILURE() << verdict_name(o.verdict) << " [" << o.c.kind << "] " << o.c.mutation << "\n  sflsh "
                  << o.c.arguments << "\n  " << o.detail;
}

std::string scene_command(const fs::path& scene, const fs::path& out) {
  return fmt::format("-q simulate --scene '{}' --out '{}'", scene.string(), out.string());
}

TEST(Fuzz, SceneToml) {
  fuzz_text_kind({"scene TOML",
                  "scene.toml",
                  [](const fs::path&) { return kScene; },
                  write_scene_inputs,
                  scene_command,
                  true,
                  {{"motion_offset", "1e9"},
                   {"motion_offset", "1e6"},
                   {"count", "100000"},
                   {"duration", "1e9"},
                   {"fps", "1e9"},
                   {"half_extents", "<delete>"},
                   {"length", "<delete>"},
                   {"max_offset", "1e300"},
                   {"spacing", "1e300"}}},
                 21);
}

TEST(Fuzz, ObjObstacle) {
  fuzz_text_kind(
      {"OBJ obstacle",
       "obstacle.obj",
       [](const fs::path&) { return kObstacle; },
       write_scene_inputs,
       [](const fs::path& in, const fs::path& out) { return scene_command(in.parent_path() / "scene.toml", out); },
       false,
       {}},
      22);
}

TEST(Fuzz, ShapeModelToml) {
  const std::string base = read_text(fs::path(SFLSH_DATA_DIR) / "shape_models" / "default.toml");
  fuzz_text_kind(
      {"shape model",
       "shape_model.toml",
       [&](const fs::path&) { return base; },
       write_scene_inputs,
       [](const fs::path& in, const fs::path& out) { return scene_command(in.parent_path() / "scene.toml", out); },
       true,
       {{"mesh", "'ultra'"}, {"region", "'torso'"}, {"poisson", "0.5"}, {"saturation", "1e308"}, {"version", "99"}}},
      23);
}

TEST(Fuzz, VerifyToml) {
  fuzz_text_kind({"verify TOML",
                  "problem.toml",
                  [](const fs::path&) { return kVerify; },
                  write_verify_inputs,
                  [](const fs::path& in, const fs::path& out) {
                    return fmt::format("-q verify '{}' --no-vtk --out '{}'", in.string(), out.string());
                  },
                  true,
                  {{"duration", "1e9"},
                   {"step", "1e-12"},
                   {"young_tangent", "1e30"},
                   {"saturation", "1e308"},
                   {"density", "1e-30"}}},
                 24);
}

TEST(Fuzz, GmshMsh) {
  fuzz_text_kind({"gmsh .msh",
                  "bar.msh",
                  [](const fs::path& dir) {
                    write_verify_inputs(dir);
                    return read_text(dir / "bar.msh");
                  },
                  write_verify_inputs,
                  [](const fs::path& in, const fs::path& out) {
                    return fmt::format("-q verify '{}' --no-vtk --out '{}'",
                                       (in.parent_path() / "problem.toml").string(), out.string());
                  },
                  false,
                  {}},
                 25);
}

}  // namespace
}  // namespace sflsh::testing::fuzz

namespace sflsh::testing::fuzz {
namespace {

/// A material file of OPEN_TRAIN_1 as `sflsh material show` writes it (4 control points, coarse layer).
std::string material_base() {
  static const std::string text = [] {
    const fs::path dir = scratch_dir() / "material_base";
    const std::string command = fmt::format(
        "{} -q material show --subject OPEN_TRAIN_1 --mesh coarse --control-points 4 --cache '{}' --out '{}'",
        SFLSH_CLI, SFLSH_TEST_CACHE, dir.string());
    if (std::system(command.c_str()) != 0) return std::string();
    return read_text(dir / "material.toml");
  }();
  return text;
}

TEST(Fuzz, MaterialToml) {
  ASSERT_FALSE(material_base().empty()) << "sflsh material show did not write material.toml";
  fuzz_text_kind({"material TOML",
                  "material.toml",
                  [](const fs::path&) { return material_base(); },
                  nullptr,
                  [](const fs::path& in, const fs::path& out) {
                    return fmt::format(
                        "-q material show --subject OPEN_TRAIN_1 --mesh coarse --material '{}' --cache '{}' --out '{}'",
                        in.string(), SFLSH_TEST_CACHE, out.string());
                  },
                  true,
                  {{"young_tangent", "1e30"},
                   {"young_normal", "0.001"},
                   {"saturation", "1e308"},
                   {"poisson", "0.5"},
                   {"body", "'smpl'"},
                   {"vertex", "99999999"},
                   {"thickness", "nan"}}},
                 26);
}

}  // namespace
}  // namespace sflsh::testing::fuzz
