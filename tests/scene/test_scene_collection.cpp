// One file opens a whole scene: scene.pvd lists every body and the objects at every written frame, in the
// world; scene_dynamics.pvd lists the σ maps, each where its body stands. The frames describe themselves
// (units, soft_region, Normals of the placed posed surface), and [output] format = "xdmf" writes one series
// per body and for the objects. Coarse layer, 30 handles, 4 frames.
#include "scratch_dir.hpp"
#include "self_described.hpp"

#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_reader.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

namespace sflsh::scene {
namespace {

namespace fs = std::filesystem;

// A soft body 1 m along +x and 0.5 m along −z with a ball pressed into its belly (the belly's front is near
// (0, 0.064, 0.119) m in the body's frame), and a skinned body turned 90° at x = −1 m.
const Eigen::Vector3d kSoftAt(1.0, 0.0, -0.5), kStillAt(-1.0, 0.0, 0.0);

nlohmann::json run_in(const fs::path& dir, const std::string& output, int frames) {
  fs::create_directories(dir);
  std::ofstream(dir / "scene.toml") << fmt::format(R"([scene]
fps = 60
frames = {0}
[effects]
inertia = true
object_contact = true
[output]
{1}
[[body]]
name = "soft"
motion = "rest"
mesh = "coarse"
handles = 30
placement = {{ position = [{2}, {3}, {4}] }}
[[body]]
name = "still"
motion = "rest"
solver = "skinned"
placement = {{ position = [{5}, {6}, {7}], yaw = 90.0 }}
[[object]]
name = "ball"
shape = "sphere"
radius = 0.06
motion = "prescribed"
keyframes = [{{ t = 0.0, position = [{2}, 0.064, {8}] }}, {{ t = 0.05, position = [{2}, 0.064, {9}] }}]
)",
                                                   frames, output, kSoftAt.x(), kSoftAt.y(), kSoftAt.z(), kStillAt.x(),
                                                   kStillAt.y(), kStillAt.z(), kSoftAt.z() + 0.19, kSoftAt.z() + 0.16);
  SceneRunOptions options;
  options.cache_dir = SFLSH_TEST_CACHE;
  options.out = dir / "out";
  options.threads = 1;
  return run_scene(load_scene(dir / "scene.toml"), options);
}

struct Entry {
  std::string time, part, name, file;
};

std::vector<Entry> collection(const fs::path& pvd) {
  std::ifstream in(pvd);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::regex entry(
      R"re(<DataSet (?:timestep="([^"]+)" )?group="" part="([0-9]+)" name="([^"]+)" file="([^"]+)"/>)re");
  std::vector<Entry> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it)
    out.push_back({(*it)[1].str(), (*it)[2].str(), (*it)[3].str(), (*it)[4].str()});
  return out;
}

Eigen::RowVector3d centroid(const fs::path& file) { return vtk::read_points(file).colwise().mean(); }

TEST(SceneCollection, ScenePvdHoldsEveryBodyAndTheObjectsPerFrameAndTheMapsArePlaced) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json s = run_in(dir, "", 4);
  const fs::path out = dir / "out";
  EXPECT_EQ(s["output"]["collections"], nlohmann::json::array({"scene.pvd", "scene_dynamics.pvd"}));

  const std::vector<Entry> entries = collection(out / "scene.pvd");
  ASSERT_EQ(entries.size(), 4u * 3u);
  for (int f = 0; f < 4; ++f) {
    const std::string names[] = {"soft", "still", "objects"};
    for (int part = 0; part < 3; ++part) {
      const Entry& e = entries[static_cast<std::size_t>(3 * f + part)];
      EXPECT_NEAR(std::stod(e.time), f / 60.0, 1e-9);
      EXPECT_EQ(e.part, std::to_string(part));
      EXPECT_EQ(e.name, names[part]);
      EXPECT_EQ(e.file, fmt::format("{}_{:06d}.vtp", names[part], f));
      EXPECT_TRUE(fs::exists(out / e.file)) << e.file;
    }
  }
  // In the world: each body's frames around its placement, the σ map on the body's first frame (rest pose).
  const Eigen::RowVector3d soft_centre = centroid(out / "soft_000000.vtp");
  EXPECT_NEAR(soft_centre.x(), kSoftAt.x(), 0.2);
  EXPECT_NEAR(soft_centre.z(), kSoftAt.z(), 0.2);
  EXPECT_NEAR(centroid(out / "still_000003.vtp").x(), kStillAt.x(), 0.2);
  const std::vector<Entry> maps = collection(out / "scene_dynamics.pvd");
  ASSERT_EQ(maps.size(), 1u);
  EXPECT_EQ(maps[0].time, "");
  EXPECT_EQ(maps[0].file, "soft_dynamics.vtp");
  EXPECT_LT((centroid(out / "soft_dynamics.vtp") - centroid(out / "soft_000000.vtp")).norm(), 0.02);

  for (const char* file : {"soft_000003.vtp", "still_000003.vtp", "objects_000003.vtp", "soft_dynamics.vtp"})
    testing::expect_self_described(out / file);

  // soft_region is 1 exactly where the soft-tissue fields live: they are 0 outside, κ is positive inside.
  const fs::path frame = out / "soft_000003.vtp";
  const Eigen::MatrixXd region = vtk::read_point_array(frame, "soft_region");
  EXPECT_EQ(region, vtk::read_point_array(out / "soft_dynamics.vtp", "soft_region"));
  EXPECT_GT(region.sum(), 100.0);
  EXPECT_LT(region.sum(), static_cast<double>(region.rows()));
  EXPECT_EQ(vtk::read_point_array(frame, "thickness_fraction"), vtk::read_point_array(frame, "thickness"));
  for (const auto& [file, name] : std::vector<std::pair<fs::path, const char*>>{{frame, "soft_tissue_displacement"},
                                                                                {frame, "elastic_displacement"},
                                                                                {frame, "strain_energy_density"},
                                                                                {frame, "thickness_fraction"},
                                                                                {frame, "young_normal"},
                                                                                {frame, "contact_force"},
                                                                                {out / "soft_dynamics.vtp", "sigma"}}) {
    const Eigen::MatrixXd values = vtk::read_point_array(file, name);
    for (Eigen::Index v = 0; v < region.rows(); ++v)
      if (region(v) == 0.0) {
        ASSERT_EQ(values.row(v).norm(), 0.0) << name << " at vertex " << v;
      }
  }
  const Eigen::MatrixXd h = vtk::read_point_array(frame, "thickness_fraction");
  const Eigen::MatrixXd sigma = vtk::read_point_array(out / "soft_dynamics.vtp", "sigma");
  for (Eigen::Index v = 0; v < region.rows(); ++v)
    if (region(v) == 1.0) {
      ASSERT_GT(h(v), 0.0) << v;
    }
  EXPECT_GT(sigma.maxCoeff(), 0.0);  // the ball moved the tissue

  // Normals: unit, those of the written (posed, placed) triangles, mostly away from the body's centre.
  const vtk::Points points = vtk::read_points(frame);
  const Eigen::MatrixXd normals = vtk::read_point_array(frame, "Normals");
  const vtk::Points expected = vtk::vertex_normals(points, vtk::read_cells(frame));
  EXPECT_LT((normals - expected).cwiseAbs().maxCoeff(), 1e-6);  // Float32
  const Eigen::RowVector3d c = points.colwise().mean();
  double outward = 0.0;
  int positive = 0;
  for (Eigen::Index v = 0; v < points.rows(); ++v) {
    EXPECT_NEAR(normals.row(v).norm(), 1.0, 1e-6);
    const double d = normals.row(v).dot(points.row(v) - c);
    outward += d;
    positive += d > 0.0;
  }
  EXPECT_GT(outward, 0.0);
  EXPECT_GT(positive, 0.7 * static_cast<double>(points.rows()));
}

TEST(SceneCollection, XdmfFormatWritesASeriesPerBodyAndForTheObjects) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json s = run_in(dir, "format = \"xdmf\"", 2);
  const fs::path out = dir / "out";
  EXPECT_EQ(s["output"]["format"], "xdmf");
  EXPECT_TRUE(s["output"]["collections"].empty());
  for (const char* file :
       {"soft.xmf", "soft.h5", "still.xmf", "still.h5", "objects.xmf", "objects.h5", "soft_dynamics.vtp"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  for (const char* file : {"scene.pvd", "soft.pvd", "soft_000001.vtp", "objects.pvd"})
    EXPECT_FALSE(fs::exists(out / file)) << file;
  std::ifstream in(out / "soft.xmf");
  std::stringstream xml;
  xml << in.rdbuf();
  EXPECT_THAT(xml.str(), ::testing::HasSubstr("<Information Name=\"units\" Value=\"skin_weights_argmax: index; "));
  EXPECT_THAT(xml.str(), ::testing::HasSubstr("soft_region: 1"));
  EXPECT_THAT(xml.str(), ::testing::HasSubstr("Normals: 1"));
  EXPECT_THAT(xml.str(), ::testing::HasSubstr("<Time Value=\"0.016666666666666666\"/>"));
  EXPECT_NEAR(centroid(out / "soft_dynamics.vtp").x(), kSoftAt.x(), 0.2);
  EXPECT_NEAR(centroid(out / "soft_dynamics.vtp").z(), kSoftAt.z(), 0.2);
  // Float32 uncompressed datasets (the crowd's settings): every series takes them, the body's, the
  // skinned body's and the objects'; the file is smaller than the Float64 zlib one.
  const fs::path dir32 = dir / "float32";
  run_in(dir32, "format = \"xdmf\"\ncompression = \"none\"\nprecision = \"float32\"", 2);
  for (const char* name : {"soft.xmf", "still.xmf", "objects.xmf"}) {
    std::ifstream series(dir32 / "out" / name);
    std::stringstream text;
    text << series.rdbuf();
    EXPECT_THAT(text.str(), ::testing::HasSubstr("NumberType=\"Float\" Precision=\"4\"")) << name;
    EXPECT_THAT(text.str(), ::testing::Not(::testing::HasSubstr("Precision=\"8\""))) << name;
  }
  // The same motion: the last positions equal the Float64 run's to Float32 rounding (~6e-8 relative at ~1 m).
  const xdmf::SeriesReader single(dir32 / "out" / "soft.xmf"), twice(out / "soft.xmf");
  ASSERT_EQ(single.steps(), twice.steps());
  EXPECT_LT((single.points(single.steps() - 1) - twice.points(twice.steps() - 1)).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
}  // namespace sflsh::scene
