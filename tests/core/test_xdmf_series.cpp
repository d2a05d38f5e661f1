// The XDMF + HDF5 time series: what is stored once and what per step, values read back with HDF5, every
// reference of the XML present in the HDF5 file, Float32 on request, and meshio's reader on the result.
#include "scratch_dir.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/xdmf_reader.hpp>
#include <sflsh/core/xdmf_series.hpp>

#include <gmock/gmock.h>
#include <hdf5.h>

#include <fstream>
#include <regex>
#include <sstream>

namespace sflsh::xdmf {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::text_of;

/// A dataset read back as doubles, with its shape.
struct Read {
  std::vector<double> values;
  std::vector<hsize_t> dims;
  bool single = false;
};

Read read_dataset(const fs::path& h5, const std::string& path) {
  Read r;
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0);
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << path;
  const hid_t space = H5Dget_space(set);
  r.dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
  H5Sget_simple_extent_dims(space, r.dims.data(), nullptr);
  hsize_t n = 1;
  for (hsize_t d : r.dims) n *= d;
  r.values.resize(n);
  const hid_t type = H5Dget_type(set);
  r.single = H5Tget_class(type) == H5T_FLOAT && H5Tget_size(type) == 4;
  H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, r.values.data());
  H5Tclose(type);
  H5Sclose(space);
  H5Dclose(set);
  H5Fclose(file);
  return r;
}

bool has_link(const fs::path& h5, const std::string& path) {
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  bool found = true;
  std::size_t at = 0;
  while (found && (at = path.find('/', at + 1)) != std::string::npos)
    found = H5Lexists(file, path.substr(0, at).c_str(), H5P_DEFAULT) > 0;
  found = found && H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0;
  H5Fclose(file);
  return found;
}

/// Two tetrahedra; step 1 keeps the nodes of step 0, step 2 moves them.
void write_three_steps(const fs::path& xmf, Precision precision,
                       vtk::Compression compression = vtk::Compression::none) {
  vtk::Points points(5, 3);
  points << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  vtk::Cells tets(2, 4);
  tets << 0, 1, 2, 3, 1, 2, 3, 4;
  Series series(xmf, tets, precision, compression);
  vtk::Fields fixed;
  fixed.cell_data.push_back({"part", (Eigen::MatrixXd(2, 1) << 2, 3).finished(), true});
  series.set_static(fixed);
  for (int k = 0; k < 3; ++k) {
    vtk::Fields f;
    f.point_data.push_back({"sigma_mm", Eigen::MatrixXd::Constant(5, 1, 0.1 * k + 1.0 / 3.0), false});
    Eigen::MatrixXd u = Eigen::MatrixXd::Zero(5, 3);
    u(4, 1) = 0.25 * k;
    f.point_data.push_back({"displacement_m", u, false});
    vtk::Points p = points;
    if (k == 2) p(4, 0) += 0.5;
    series.write(0.1 * k, p, f);
  }
  EXPECT_EQ(series.steps(), 3u);
}

TEST(XdmfSeries, StoresTopologyAndStaticFieldsOnceAndEachStepsFields) {
  const fs::path dir = sflsh::testing::scratch_dir();
  write_three_steps(dir / "body.xmf", Precision::float64);
  const fs::path h5 = dir / "body.h5";
  const Read topology = read_dataset(h5, "/topology");
  EXPECT_THAT(topology.dims, ::testing::ElementsAre(2, 4));
  EXPECT_THAT(topology.values, ::testing::ElementsAre(0, 1, 2, 3, 1, 2, 3, 4));
  EXPECT_TRUE(has_link(h5, "/geometry/000000"));
  EXPECT_FALSE(has_link(h5, "/geometry/000001"));  // the nodes did not move: no copy
  EXPECT_TRUE(has_link(h5, "/geometry/000002"));
  EXPECT_EQ(read_dataset(h5, "/geometry/000002").values[12], 1.5);
  const Read u = read_dataset(h5, "/point/displacement_m/000002");
  EXPECT_THAT(u.dims, ::testing::ElementsAre(5, 3));
  EXPECT_EQ(u.values[4 * 3 + 1], 0.5);  // row-major: node 4, component y
  EXPECT_EQ(read_dataset(h5, "/point/sigma_mm/000001").values[0], 0.1 + 1.0 / 3.0);
  EXPECT_FALSE(read_dataset(h5, "/point/sigma_mm/000001").single);
  EXPECT_THAT(read_dataset(h5, "/static/cell/part").values, ::testing::ElementsAre(2, 3));

  const std::string xml = text_of(dir / "body.xmf");
  EXPECT_EQ(std::count(xml.begin(), xml.end(), '\n') > 10, true);
  const std::regex reference("body\\.h5:(/[A-Za-z0-9_/]+)");
  int references = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), reference); it != std::sregex_iterator();
       ++it, ++references)
    EXPECT_TRUE(has_link(h5, (*it)[1].str())) << (*it)[1].str();
  EXPECT_EQ(references, 3 * 5);  // per step: topology, geometry, part, sigma_mm, displacement_m
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(<Time Value="0.20000000000000001"/>)"));
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(AttributeType="Vector" Center="Node")"));
  EXPECT_THAT(xml, ::testing::HasSubstr(R"(TopologyType="Tetrahedron" NumberOfElements="2")"));
}

TEST(XdmfSeries, Float32OnRequest) {
  const fs::path dir = sflsh::testing::scratch_dir();
  write_three_steps(dir / "body.xmf", Precision::float32);
  const Read sigma = read_dataset(dir / "body.h5", "/point/sigma_mm/000000");
  EXPECT_TRUE(sigma.single);
  EXPECT_EQ(sigma.values[0], static_cast<double>(static_cast<float>(1.0 / 3.0)));
  EXPECT_THAT(text_of(dir / "body.xmf"), ::testing::HasSubstr(R"(NumberType="Float" Precision="4")"));
}

/// Number of filters of a dataset's creation property list (shuffle + deflate: 2; contiguous: 0).
int filters(const fs::path& h5, const std::string& path) {
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  const hid_t plist = H5Dget_create_plist(set);
  const int n = H5Pget_nfilters(plist);
  H5Pclose(plist);
  H5Dclose(set);
  H5Fclose(file);
  return n;
}

TEST(XdmfSeries, ZlibCompressesEveryDatasetAndReadsBackTheSameValues) {
  const fs::path dir = sflsh::testing::scratch_dir();
  write_three_steps(dir / "plain.xmf", Precision::float64);
  write_three_steps(dir / "packed.xmf", Precision::float64, vtk::Compression::zlib);
  for (const char* path : {"/topology", "/geometry/000002", "/point/displacement_m/000001", "/static/cell/part"}) {
    EXPECT_EQ(filters(dir / "plain.h5", path), 0) << path;
    EXPECT_EQ(filters(dir / "packed.h5", path), 2) << path;  // shuffle, deflate
    EXPECT_EQ(read_dataset(dir / "packed.h5", path).values, read_dataset(dir / "plain.h5", path).values) << path;
  }
  vtk::Cells tets(1, 4);
  tets << 0, 1, 2, 3;
  EXPECT_THROW(Series(dir / "lz4.xmf", tets, Precision::float32, vtk::Compression::lz4), Error);
}

TEST(XdmfSeriesReader, ReadsStepsTimesPointsAndArraysBack) {
  const fs::path dir = sflsh::testing::scratch_dir();
  write_three_steps(dir / "body.xmf", Precision::float32, vtk::Compression::zlib);
  const SeriesReader reader(dir / "body.xmf");
  ASSERT_EQ(reader.steps(), 3u);
  EXPECT_DOUBLE_EQ(reader.time(2), 0.2);
  EXPECT_EQ(reader.cells().rows(), 2);
  EXPECT_EQ(reader.cells()(1, 3), 4);
  EXPECT_EQ(reader.points(1)(4, 0), 1.0);  // step 1 reuses step 0's nodes
  EXPECT_EQ(reader.points(2)(4, 0), 1.5);
  EXPECT_THAT(reader.point_array_names(0), ::testing::ElementsAre("sigma_mm", "displacement_m"));
  EXPECT_EQ(reader.point_array(2, "displacement_m")(4, 1), 0.5);
  EXPECT_EQ(reader.point_array(0, "sigma_mm")(0, 0), static_cast<double>(static_cast<float>(1.0 / 3.0)));
  try {
    (void)reader.point_array(1, "velocity");
    ADD_FAILURE() << "no error for a missing array";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(),
                ::testing::HasSubstr("step 1 has no node array 'velocity' (it has: sigma_mm, displacement_m)"));
  }
  EXPECT_THROW((void)reader.points(3), Error);
}

TEST(XdmfSeriesReader, RefusesWhatIsNotSuchASeriesInOneLine) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const auto message = [&](const std::string& xml) {
    std::ofstream(dir / "bad.xmf") << xml;
    try {
      SeriesReader reader(dir / "bad.xmf");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message("not xml at all <"), ::testing::HasSubstr("bad.xmf: not an XDMF file"));
  EXPECT_THAT(message("<Xdmf><Domain><Grid Name=\"a\"/></Domain></Xdmf>"),
              ::testing::HasSubstr("expected a temporal collection"));
  EXPECT_THAT(message("<Xdmf><Domain><Grid CollectionType=\"Temporal\"></Grid></Domain></Xdmf>"),
              ::testing::HasSubstr("the series has no steps"));
  {  // cells naming a node the geometry does not have: refused before anything draws them
    vtk::Cells tets(1, 4);
    tets << 0, 1, 2, 7;
    Series series(dir / "index.xmf", tets);
    series.write(0.0, vtk::Points::Zero(5, 3), {});
  }
  EXPECT_THROW((void)SeriesReader(dir / "index.xmf").cells(), Error);
  write_three_steps(dir / "body.xmf", Precision::float64);
  fs::remove(dir / "body.h5");
  EXPECT_THROW(SeriesReader(dir / "body.xmf"), Error);
  EXPECT_THROW(SeriesReader(dir / "missing.xmf"), Error);
}

TEST(XdmfSeries, MeshioReadsTheSeries) {
  if (std::system("/usr/bin/python3 -c 'import meshio' >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3-meshio is not installed";
  const fs::path dir = sflsh::testing::scratch_dir();
  write_three_steps(dir / "body.xmf", Precision::float64, vtk::Compression::zlib);  // HDF5 filters too
  const fs::path script = dir / "read.py";
  std::ofstream(script)
      << "import meshio\n"
         "with meshio.xdmf.TimeSeriesReader('"
      << (dir / "body.xmf").string()
      << "') as r:\n"
         "    points, cells = r.read_points_cells()\n"
         "    t, point_data, cell_data = r.read_data(2)\n"
         "    print(r.num_steps, len(points), cells[0].type, len(cells[0].data), t, point_data['displacement_m'][4][1],"
         " cell_data['part'][0][1])\n";
  const std::string command = "/usr/bin/python3 " + script.string() + " > " + (dir / "out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << text_of(dir / "out.txt");
  EXPECT_EQ(text_of(dir / "out.txt"), "3 5 tetra 2 0.2 0.5 3\n");
}

}  // namespace
}  // namespace sflsh::xdmf
