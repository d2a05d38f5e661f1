// What a scene writes: [output] every writes exactly the chosen frames (the first and the last always) and the
// .pvd lists exactly them with their times; [output] fields restricts the frames' arrays; bad values are one
// error naming the file, line and key. Coarse layer, 30 handles, a few frames.
#include "error_of.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/vtk_io.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <set>

namespace sflsh::scene {
namespace {

std::filesystem::path write_output_scene(const std::filesystem::path& dir, const std::string& output) {
  std::filesystem::create_directories(dir);
  const auto path = dir / "scene.toml";
  std::ofstream(path) << fmt::format(R"([scene]
fps = 60
frames = 8
[effects]
inertia = true
object_contact = true
[output]
{}
[[body]]
name = "b"
motion = "rest"
mesh = "coarse"
handles = 30
[[object]]
name = "ball"
shape = "sphere"
radius = 0.06
motion = "prescribed"
keyframes = [{{ t = 0.0, position = [0.0, 0.064, 0.19] }}, {{ t = 0.12, position = [0.0, 0.064, 0.16] }}]
)",
                                     output);
  return path;
}

nlohmann::json run_in(const std::filesystem::path& dir, const std::string& output) {
  SceneRunOptions options;
  options.cache_dir = SFLSH_TEST_CACHE;
  options.out = dir / "out";
  options.threads = 1;
  return run_scene(load_scene(write_output_scene(dir, output)), options);
}

/// The (time, file) entries of a .pvd, in order.
std::vector<std::pair<double, std::string>> pvd_entries(const std::filesystem::path& pvd) {
  std::ifstream in(pvd);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::regex entry(R"re(timestep="([^"]+)"[^>]*file="([^"]+)")re");
  std::vector<std::pair<double, std::string>> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it)
    out.emplace_back(std::stod((*it)[1].str()), (*it)[2].str());
  return out;
}

/// The files of `dir` whose names start with `prefix` and end with `extension`, sorted.
std::vector<std::string> files_of(const std::filesystem::path& dir, const std::string& prefix,
                                  const std::string& extension) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.starts_with(prefix) && name.ends_with(extension)) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SceneOutput, EveryWritesExactlyTheChosenFramesWithTheirTimes) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json s = run_in(dir, "every = 3");
  EXPECT_EQ(s["output"]["every"], 3);
  const auto out = dir / "out";
  // 8 frames, every 3rd: 0, 3, 6, and the last one, 7.
  const std::vector<int> frames = {0, 3, 6, 7};
  for (const std::string prefix : {"b", "objects"}) {
    SCOPED_TRACE(prefix);
    std::vector<std::string> expected;
    for (int f : frames) expected.push_back(fmt::format("{}_{:06d}.vtp", prefix, f));
    EXPECT_EQ(files_of(out, prefix + "_0", ".vtp"), expected);
    const auto entries = pvd_entries(out / (prefix + ".pvd"));
    ASSERT_EQ(entries.size(), frames.size());
    for (std::size_t k = 0; k < frames.size(); ++k) {
      EXPECT_EQ(entries[k].second, expected[k]);
      EXPECT_NEAR(entries[k].first, frames[k] / 60.0, 1e-9);
    }
  }
  // σ still sees every frame.
  EXPECT_EQ(s["bodies"][0]["dynamics"]["frames"], 8);
}

TEST(SceneOutput, FieldsRestrictTheArraysAndEveryOneIsTheDefault) {
  const auto dir = testing::scratch_dir();
  run_in(dir / "some", R"(fields = ["elastic_displacement", "contact_force"])");
  const auto names = vtk::read_point_array_names(dir / "some" / "out" / "b_000007.vtp");
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()),
            (std::set<std::string>{"elastic_displacement", "contact_force"}));
  run_in(dir / "none", "fields = []\nevery = 7");
  EXPECT_TRUE(vtk::read_point_array_names(dir / "none" / "out" / "b_000007.vtp").empty());
  run_in(dir / "all", "compression = \"zlib\"");
  const auto all = vtk::read_point_array_names(dir / "all" / "out" / "b_000007.vtp");
  for (const char* name :
       {"displacement", "velocity", "skin_weights_argmax", "soft_tissue_displacement", "elastic_displacement",
        "strain_energy_density", "thickness", "young_tangent", "young_normal", "contact_force", "penetration"})
    EXPECT_NE(std::find(all.begin(), all.end(), name), all.end()) << name;
  // The restricted frame holds the same values as the full one.
  EXPECT_EQ(vtk::read_point_array(dir / "some" / "out" / "b_000007.vtp", "elastic_displacement"),
            vtk::read_point_array(dir / "all" / "out" / "b_000007.vtp", "elastic_displacement"));
}

TEST(SceneOutput, BadOutputValuesAreOneLineNamingTheKey) {
  const auto dir = testing::scratch_dir();
  struct Case {
    std::string output, expected;
  };
  for (const Case& c : std::vector<Case>{
           {"every = 0", "scene.toml:8: 'every' in [output] = 0 must be an integer in [1, 10⁶]"},
           {"every = 1000000000", "scene.toml:8: 'every' in [output] = 1000000000 must be an integer in [1, 10⁶]"},
           {"every = 1.5", "scene.toml:8: 'every'"},
           {R"(fields = ["displacement", "sigma"])",
            "scene.toml:8: unknown field 'sigma' in 'fields' of [output] (expected all, default, or some of"},
           {R"(fields = "displacement")", "scene.toml:8: 'fields' in [output] must be an array of strings"},
           {R"(compression = "gzip")",
            "scene.toml:8: 'compression' in [output] = 'gzip' is not one of lz4 | zlib | none"},
           {"compression = \"lz4\"\nformat = \"xdmf\"",
            "scene.toml:8: 'compression' in [output]: lz4 is not available for the HDF5 datasets of format xdmf"},
           {R"(precision = "float16")",
            "scene.toml:8: 'precision' in [output] = 'float16' is not one of float64 | float32"},
       }) {
    SCOPED_TRACE(c.output);
    const auto path = write_output_scene(dir, c.output);
    const std::string message = testing::error_of([&] { load_scene(path); });
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace sflsh::scene
