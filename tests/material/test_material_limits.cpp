// Material files against the physical limits (parameters.hpp: Young moduli in [1, 1e9] Pa, saturation in
// (0, 100]), a file argument that is a directory, a material for another body, and messages that name the
// file (never a bare "material:").
#include "error_of.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/body_model.hpp>
#include <sflsh/material/material_file.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

namespace sflsh {

using namespace sflsh::material;
using sflsh::testing::error_of;
using ::testing::HasSubstr;

namespace {

std::string material_text(const std::string& saturation, const std::string& young_bounds, const std::string& young) {
  return "version = 1\n"           // 1
         "body = \"open_body\"\n"  // 2
         "subject = \"S\"\n"       // 3
         "poisson = 0.2\n"         // 4
         "saturation = " +
         saturation +
         "\n"          // 5
         "[bounds]\n"  // 6
         "young_tangent = " +
         young_bounds +
         "\n"                   // 7
         "[[control_point]]\n"  // 8
         "vertex = 3\n"         // 9
         "thickness = 0.5\n"    // 10
         "young_tangent = " +
         young +
         "\n"                        // 11
         "young_normal = 2000.0\n";  // 12
}

std::filesystem::path write(const std::filesystem::path& dir, const std::string& text) {
  const auto path = dir / "m.toml";
  std::ofstream(path) << text;
  return path;
}

TEST(MaterialLimits, SaturationAndYoungModuliOutsideThePhysicalRangeAreRefusedAtLoad) {
  const auto dir = sflsh::testing::scratch_dir();
  EXPECT_NO_THROW(load_material_file(write(dir, material_text("4.0", "[500.0, 50000.0]", "5000.0"))));
  const std::string huge =
      error_of([&] { load_material_file(write(dir, material_text("1e308", "[500.0, 50000.0]", "5000.0"))); });
  EXPECT_THAT(huge, HasSubstr("m.toml:5: saturation: 1e+308 is outside (0, 100]")) << huge;
  const std::string stiff =
      error_of([&] { load_material_file(write(dir, material_text("4.0", "[500.0, 1e31]", "1e30"))); });
  EXPECT_THAT(stiff, HasSubstr("m.toml:7:")) << stiff;
  EXPECT_THAT(stiff, HasSubstr("young_tangent = [500, 1e+31] Pa is outside the physical range [1, 1e+09] Pa")) << stiff;
}

TEST(MaterialLimits, ADirectoryOrMissingFileSaysSo) {
  const auto dir = sflsh::testing::scratch_dir();
  std::filesystem::create_directories(dir / "a_directory.toml");
  EXPECT_THAT(error_of([&] { load_material_file(dir / "a_directory.toml"); }),
              HasSubstr("a_directory.toml: is a directory, expected a material TOML file"));
  EXPECT_THAT(error_of([&] { load_material_file(dir / "absent.toml"); }),
              HasSubstr("absent.toml: not found, expected a material TOML file"));
}

TEST(MaterialLimits, AMaterialForAnotherBodyIsRefusedNamingTheFileAndBoth) {
  const auto dir = sflsh::testing::scratch_dir();
  std::string text = material_text("4.0", "[500.0, 50000.0]", "5000.0");
  text.replace(text.find("open_body"), 9, "smpl");
  const auto path = write(dir, text);
  const MaterialFile file = load_material_file(path);
  body::BodyModel open;
  open.name = "open_body";
  open.v_template = RowMatrixX3d::Zero(10, 3);
  const std::string message = error_of([&] { check_against_body(file, open); });
  EXPECT_THAT(message,
              HasSubstr(path.string() + ": body: the material is for body 'smpl', but the run uses body 'open_body'"))
      << message;
}

TEST(MaterialLimits, BodyChecksNameTheFileAndLineNotABareMaterial) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = write(dir, material_text("4.0", "[500.0, 50000.0]", "5000.0"));
  const MaterialFile file = load_material_file(path);
  body::BodyModel small;
  small.name = "open_body";
  small.v_template = RowMatrixX3d::Zero(2, 3);  // vertex 3 does not exist
  const std::string message = error_of([&] { check_against_body(file, small); });
  EXPECT_THAT(message, HasSubstr(path.string() + ":8: control_point #0 'vertex' = 3 is outside the body's 2 vertices"))
      << message;
  EXPECT_EQ(message.rfind("material:", 0), std::string::npos) << message;
}

}  // namespace

}  // namespace sflsh
