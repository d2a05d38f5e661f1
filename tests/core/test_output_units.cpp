// Self-describing output: the `units` field data names every array's unit, label names travel as text field
// data (UTF-8 in UInt8 arrays, which meshio reads, not VTK string arrays), surfaces carry unit outward normals, a .pvd
// lists parts with names, an xdmf series says its units, and every name of the units table (core/array_units.cpp) has
// its row in docs/output.md.
#include "scratch_dir.hpp"
#include "self_described.hpp"

#include <sflsh/core/array_units.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_series.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <hdf5.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace sflsh {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::text_of;

/// A closed octahedron around (1, 2, 3), triangles counter-clockwise seen from outside.
void octahedron(vtk::Points& points, vtk::Cells& triangles) {
  points.resize(6, 3);
  points << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  points.rowwise() += Eigen::RowVector3d(1, 2, 3);
  triangles.resize(8, 3);
  triangles << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
}

TEST(ArrayUnits, NamesFamiliesAndUnknownNames) {
  EXPECT_EQ(units::of("displacement"), "m");
  EXPECT_EQ(units::of("sigma"), "mm");
  EXPECT_EQ(units::of("sigma_reduced_h30_k200"), "mm");
  EXPECT_EQ(units::of("phi_07"), "1");
  EXPECT_EQ(units::of("thickness"), units::of("thickness_fraction"));
  EXPECT_EQ(units::of("strain_energy_density"), "J/m^3");
  EXPECT_EQ(units::of("no_such_array"), "");
  EXPECT_EQ(units::entry("velocity"), "velocity: m/s");
  EXPECT_EQ(units::entry("no_such_array"), "no_such_array: ?");
}

TEST(ArrayUnits, EveryNameHasItsRowInTheOutputDocs) {
  const std::string docs = text_of(fs::path(SFLSH_DATA_DIR).parent_path() / "docs" / "output.md");
  ASSERT_FALSE(docs.empty());
  for (const std::string& name : units::listed_names())
    EXPECT_THAT(docs, ::testing::HasSubstr(fmt::format("| `{}`", name))) << name;
  for (const units::Family& f : units::families())
    EXPECT_THAT(docs, ::testing::HasSubstr(fmt::format("`{}", f.prefix))) << f.prefix;
}

TEST(VtkOutput, UnitsLabelsAndNormalsAreWrittenBesideTheArrays) {
  const auto dir = testing::scratch_dir();
  vtk::Points points;
  vtk::Cells triangles;
  octahedron(points, triangles);
  vtk::Fields fields;
  fields.point_data.push_back({"displacement", Eigen::MatrixXd::Constant(6, 3, 0.5), false});
  fields.point_data.push_back({"part", (Eigen::MatrixXd(6, 1) << 0, 1, 2, 0, 1, 2).finished(), true});
  fields.cell_data.push_back({"volume", Eigen::MatrixXd::Ones(8, 1), false});
  fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, 0.5), false});
  fields.labels.push_back({"part_names", {"torso", "left_upper_arm", "right_upper_arm"}});
  vtk::write_surface(dir / "s.vtp", points, triangles, fields);
  testing::expect_self_described(dir / "s.vtp");
  EXPECT_THAT(vtk::read_field_strings(dir / "s.vtp", "units"),
              ::testing::ElementsAre("displacement: m", "part: label", "Normals: 1", "volume: m^3", "TimeValue: s"));
  testing::expect_labels_named(dir / "s.vtp", vtk::read_point_array(dir / "s.vtp", "part"), "part_names");
  // Text as UInt8 (meshio 7's VTU reader refuses the type "String"), one line per value.
  const std::string xml = text_of(dir / "s.vtp");
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(<DataArray type="UInt8" Name="units")"));
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(<DataArray type="UInt8" Name="part_names")"));
  EXPECT_THAT(xml, ::testing::Not(::testing::HasSubstr(R"(type="String")")));
  const Eigen::MatrixXd names = vtk::read_field_array(dir / "s.vtp", "part_names");
  std::string joined;
  for (Eigen::Index k = 0; k < names.rows(); ++k) joined += static_cast<char>(names(k, 0));
  EXPECT_EQ(joined, "torso\nleft_upper_arm\nright_upper_arm");

  // Unit normals pointing away from the centre, computed from the written triangles.
  const Eigen::MatrixXd normals = vtk::read_point_array(dir / "s.vtp", "Normals");
  ASSERT_EQ(normals.rows(), 6);
  const Eigen::RowVector3d centre = points.colwise().mean();
  for (Eigen::Index v = 0; v < 6; ++v) {
    EXPECT_NEAR(normals.row(v).norm(), 1.0, 1e-6);  // stored as Float32
    EXPECT_NEAR(normals.row(v).dot((points.row(v) - centre).normalized()), 1.0, 1e-6) << v;
  }
  EXPECT_EQ(vtk::read_cells(dir / "s.vtp"), triangles);

  // No normals when asked, none on a point cloud; a volume mesh's units too; an unknown name says "?".
  fields.normals = false;
  vtk::write_surface(dir / "plain.vtp", points, triangles, fields);
  EXPECT_THAT(vtk::read_point_array_names(dir / "plain.vtp"), ::testing::ElementsAre("displacement", "part"));
  vtk::write_surface(dir / "cloud.vtp", points, vtk::Cells(0, 3), {});
  EXPECT_TRUE(vtk::read_point_array_names(dir / "cloud.vtp").empty());
  vtk::Cells tet(1, 4);
  tet << 0, 1, 2, 4;
  vtk::Fields odd;
  odd.point_data.push_back({"no_such_array", Eigen::MatrixXd::Zero(6, 1), false});
  vtk::write_unstructured(dir / "t.vtu", points, tet, odd);
  EXPECT_THAT(vtk::read_field_strings(dir / "t.vtu", "units"), ::testing::ElementsAre("no_such_array: ?"));
}

TEST(VtkOutput, CollectionListsPartsWithNamesAndUntimedFiles) {
  const auto dir = testing::scratch_dir();
  vtk::PvdSeries scene(dir / "scene.pvd");
  scene.add(0.0, "a_000000.vtp", 0, "a");
  scene.add(0.0, "objects_000000.vtp", 1, "objects");
  scene.add_untimed("a_dynamics.vtp", 0, "a");
  scene.write();
  const std::string xml = text_of(dir / "scene.pvd");
  EXPECT_THAT(xml, ::testing::HasSubstr(
                       R"(<DataSet timestep="0" group="" part="1" name="objects" file="objects_000000.vtp"/>)"));
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(<DataSet group="" part="0" name="a" file="a_dynamics.vtp"/>)"));
}

/// The string attribute `unit` of a dataset.
std::string unit_attribute(const fs::path& h5, const std::string& path) {
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t attribute = H5Aopen_by_name(file, path.c_str(), "unit", H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(attribute, 0) << path;
  const hid_t type = H5Aget_type(attribute);
  std::vector<char> value(H5Tget_size(type) + 1, '\0');
  H5Aread(attribute, type, value.data());
  H5Tclose(type);
  H5Aclose(attribute);
  H5Fclose(file);
  return std::string(value.data());
}

TEST(XdmfSeries, DatasetsAndTheDomainSayTheirUnitsAndLabelNames) {
  const auto dir = testing::scratch_dir();
  vtk::Points points;
  vtk::Cells triangles;
  octahedron(points, triangles);
  {
    xdmf::Series series(dir / "s.xmf", triangles);
    vtk::Fields fixed;
    fixed.point_data.push_back({"part", Eigen::MatrixXd::Zero(6, 1), true});
    fixed.labels.push_back({"part_names", {"torso", "left_upper_arm"}});
    series.set_static(fixed);
    vtk::Fields f;
    f.point_data.push_back({"velocity", Eigen::MatrixXd::Zero(6, 3), false});
    series.write(0.0, points, f);
  }
  EXPECT_EQ(unit_attribute(dir / "s.h5", "/geometry/000000"), "m");
  EXPECT_EQ(unit_attribute(dir / "s.h5", "/point/velocity/000000"), "m/s");
  EXPECT_EQ(unit_attribute(dir / "s.h5", "/static/point/part"), "label");
  const std::string xml = text_of(dir / "s.xmf");
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(<Information Name="units" Value="part: label; velocity: m/s"/>)"));
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(<Information Name="part_names" Value="torso; left_upper_arm"/>)"));
}

}  // namespace
}  // namespace sflsh
