// gmsh .msh reading and writing: hand-written 2.2 and 4.1 files (sparse node tags, physical names,
// a flipped tet), exact round trips, the structured box mesh, and one-line errors for malformed files.
#include "error_of.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/msh_reader.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <random>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::error_of;
using sflsh::testing::scratch_dir;

using sflsh::testing::write_text;

double signed_volume(const MshMesh& mesh, int e) {
  Eigen::Matrix3d dm;
  for (int c = 0; c < 3; ++c)
    dm.col(c) = (mesh.nodes.row(mesh.tets(e, c + 1)) - mesh.nodes.row(mesh.tets(e, 0))).transpose();
  return dm.determinant() / 6.0;
}

std::vector<int> sorted_row(const MshMesh& mesh, int e) {
  std::vector<int> v{mesh.tets(e, 0), mesh.tets(e, 1), mesh.tets(e, 2), mesh.tets(e, 3)};
  std::sort(v.begin(), v.end());
  return v;
}

// Node tags 10, 3, 7, 20, 5, 99 (sparse, unsorted; 99 used only by a point); the second tet is
// written negatively oriented; a triangle in the named surface "top" and a point in the unnamed group 9.
const char* kV22 = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Comments
anything at all, even 1 2 3
$EndComments
$PhysicalNames
2
3 1 "body"
2 5 "top"
$EndPhysicalNames
$Nodes
6
10 0 0 0
3 1 0 0
7 0 1 0
20 0 0 1
5 1 1 1
99 5 5 5
$EndNodes
$Elements
4
1 15 2 9 1 99
2 2 2 5 1 7 20 5
3 4 2 1 1 10 3 7 20
4 4 2 1 1 3 20 7 5
$EndElements
$NodeData
1
"u"
$EndNodeData
)";

TEST(MshReader, ReadsV22WithSparseTagsNamesAndFlipsANegativeTet) {
  const fs::path dir = scratch_dir();
  const MshMesh mesh = read_msh(write_text(dir / "small22.msh", kV22));
  EXPECT_EQ(mesh.version, MshVersion::v22);
  ASSERT_EQ(mesh.nodes.rows(), 6);
  EXPECT_EQ(mesh.nodes.row(1), Eigen::RowVector3d(1, 0, 0));  // tag 3: second in file order
  EXPECT_EQ(mesh.nodes.row(5), Eigen::RowVector3d(5, 5, 5));  // tag 99: unused by tets, kept
  ASSERT_EQ(mesh.tets.rows(), 2);
  EXPECT_EQ(mesh.flipped_tets, 1);
  EXPECT_EQ(sorted_row(mesh, 0), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(sorted_row(mesh, 1), (std::vector<int>{1, 2, 3, 4}));
  for (int e = 0; e < 2; ++e) EXPECT_GT(signed_volume(mesh, e), 0.0) << e;
  EXPECT_EQ(mesh.node_groups.at("body"), (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(mesh.node_groups.at("top"), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(mesh.node_groups.at("9"), (std::vector<int>{5}));
  EXPECT_EQ(mesh.node_groups.size(), 3u);
  EXPECT_EQ(mesh.group_dimension.at("body"), 3);
  EXPECT_EQ(mesh.group_dimension.at("top"), 2);
  EXPECT_EQ(mesh.group_dimension.at("9"), 0);
}

// The same mesh in 4.1: node 99 comes first (its own point entity block), then 10, 3, 7, 20, 5.
const char* kV41 = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
3 1 "body"
2 5 "top"
$EndPhysicalNames
$Entities
1 0 1 1
1 5 5 5 1 9
1 0 0 0 1 1 1 1 5 0
1 0 0 0 1 1 1 1 1 1 1
$EndEntities
$Nodes
2 6 3 99
0 1 0 1
99
5 5 5
3 1 0 5
10
3
7
20
5
0 0 0
1 0 0
0 1 0
0 0 1
1 1 1
$EndNodes
$Elements
3 4 1 4
0 1 15 1
1 99
2 1 2 1
2 7 20 5
3 1 4 2
3 10 3 7 20
4 3 20 7 5
$EndElements
)";

TEST(MshReader, ReadsV41WithEntitiesAndPhysicalGroups) {
  const fs::path dir = scratch_dir();
  const MshMesh mesh = read_msh(write_text(dir / "small41.msh", kV41));
  EXPECT_EQ(mesh.version, MshVersion::v41);
  ASSERT_EQ(mesh.nodes.rows(), 6);
  EXPECT_EQ(mesh.nodes.row(0), Eigen::RowVector3d(5, 5, 5));
  EXPECT_EQ(mesh.nodes.row(2), Eigen::RowVector3d(1, 0, 0));
  ASSERT_EQ(mesh.tets.rows(), 2);
  EXPECT_EQ(mesh.flipped_tets, 1);
  EXPECT_EQ(sorted_row(mesh, 0), (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(sorted_row(mesh, 1), (std::vector<int>{2, 3, 4, 5}));
  for (int e = 0; e < 2; ++e) EXPECT_GT(signed_volume(mesh, e), 0.0) << e;
  EXPECT_EQ(mesh.node_groups.at("body"), (std::vector<int>{1, 2, 3, 4, 5}));
  EXPECT_EQ(mesh.node_groups.at("top"), (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(mesh.node_groups.at("9"), (std::vector<int>{0}));
  EXPECT_EQ(mesh.group_dimension.at("top"), 2);
  EXPECT_EQ(mesh.group_dimension.at("9"), 0);
}

TEST(MshWriter, RoundTripIsExactInBothVersions) {
  const fs::path dir = scratch_dir();
  MshMesh box = box_tet_mesh(Eigen::Vector3d(0.1, 0.07, 0.03), {3, 2, 2});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);
  for (Eigen::Index v = 0; v < box.nodes.rows(); ++v) {
    for (int c = 0; c < 3; ++c) box.nodes(v, c) += jitter(rng);  // full 17-digit coordinates
  }
  box.node_groups["empty"] = {};
  for (const MshVersion version : {MshVersion::v22, MshVersion::v41}) {
    const fs::path path = dir / (version == MshVersion::v22 ? "box22.msh" : "box41.msh");
    write_msh(path, box.nodes, box.tets, box.node_groups, version);
    const MshMesh back = read_msh(path);
    EXPECT_EQ(back.version, version);
    ASSERT_EQ(back.nodes.rows(), box.nodes.rows());
    EXPECT_TRUE(back.nodes == box.nodes);  // bit for bit
    EXPECT_TRUE(back.tets == box.tets);
    EXPECT_EQ(back.flipped_tets, 0);
    for (const auto& [name, nodes] : box.node_groups) {
      ASSERT_EQ(back.node_groups.count(name), 1u) << name;
      EXPECT_EQ(back.node_groups.at(name), nodes) << name;
      EXPECT_EQ(back.group_dimension.at(name), 0) << name;
    }
    EXPECT_EQ(back.node_groups.at("volume"), box.node_groups.at("all"));
    EXPECT_EQ(back.group_dimension.at("volume"), 3);
    EXPECT_EQ(back.node_groups.size(), box.node_groups.size() + 1);
  }
  EXPECT_NE(error_of([&] {
              write_msh(dir / "bad.msh", box.nodes, box.tets, {{"volume", {0}}});
            }).find("reserved"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "bad.msh"));
}

TEST(MshBox, TetsArePositiveConformingAndFillTheBox) {
  const Eigen::Vector3d size(0.3, 0.2, 0.1);
  const std::array<int, 3> cells{3, 2, 4};
  const MshMesh mesh = box_tet_mesh(size, cells);
  ASSERT_EQ(mesh.nodes.rows(), 4 * 3 * 5);
  ASSERT_EQ(mesh.tets.rows(), 6 * 3 * 2 * 4);
  double volume = 0.0;
  std::map<std::array<int, 3>, int> faces;
  for (int e = 0; e < mesh.tets.rows(); ++e) {
    const double v = signed_volume(mesh, e);
    EXPECT_GT(v, 0.0) << e;
    volume += v;
    const std::vector<int> t = sorted_row(mesh, e);
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f{};
      for (int a = 0, k = 0; a < 4; ++a) {
        if (a != skip) f[static_cast<std::size_t>(k++)] = t[static_cast<std::size_t>(a)];
      }
      ++faces[f];
    }
  }
  EXPECT_NEAR(volume, size.prod(), 1e-15);
  // Conforming: every face is shared by two tets or lies on the boundary (2 triangles per boundary square).
  int boundary = 0;
  for (const auto& [f, count] : faces) {
    EXPECT_LE(count, 2);
    boundary += count == 1 ? 1 : 0;
  }
  EXPECT_EQ(boundary, 2 * 2 * (3 * 2 + 2 * 4 + 3 * 4));
  EXPECT_EQ(mesh.node_groups.at("xmin").size(), 3u * 5u);
  EXPECT_EQ(mesh.node_groups.at("xmax").size(), 3u * 5u);
  EXPECT_EQ(mesh.node_groups.at("ymin").size(), 4u * 5u);
  EXPECT_EQ(mesh.node_groups.at("zmax").size(), 4u * 3u);
  EXPECT_EQ(mesh.node_groups.at("all").size(), 60u);
  EXPECT_EQ(mesh.group_dimension.at("zmax"), 2);
  for (const int v : mesh.node_groups.at("xmax")) EXPECT_DOUBLE_EQ(mesh.nodes(v, 0), size[0]);
  for (const int v : mesh.node_groups.at("zmin")) EXPECT_EQ(mesh.nodes(v, 2), 0.0);
  EXPECT_EQ(mesh.nodes.row(1), Eigen::RowVector3d(size[0] / 3, 0.0, 0.0));  // x fastest
  EXPECT_EQ(box_tet_mesh(Eigen::Vector3d(0.1, 0.02, 0.02), {5, 1, 1}).node_groups.at("xmax").size(), 4u);
}

/// The error of reading `text` as bad.msh; checks it names the file and the given line.
std::string bad_file_error(const std::string& text, int line) {
  const fs::path dir = scratch_dir();
  const fs::path path = write_text(dir / "bad.msh", text);
  const std::string message = error_of([&] { read_msh(path); });
  EXPECT_NE(message.find(path.string() + ":" + std::to_string(line) + ":"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  return message;
}

const std::string kHead22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

TEST(MshReader, MalformedFilesGiveOneLineErrorsWithFileAndLine) {
  // Truncated $Nodes: 3 announced, 2 given.
  EXPECT_NE(bad_file_error(kHead22 + "$Nodes\n3\n1 0 0 0\n2 1 0 0\n$EndNodes\n", 8).find("$Nodes"), std::string::npos);
  // The file ends inside $Nodes.
  EXPECT_NE(bad_file_error(kHead22 + "$Nodes\n3\n1 0 0 0\n", 6).find("ends early"), std::string::npos);
  // A bad number.
  const std::string bad = bad_file_error(kHead22 + "$Nodes\n2\n1 0 0 0\n2 1 abc 0\n$EndNodes\n", 7);
  EXPECT_NE(bad.find("expected 4 numbers (tag x y z), got '2 1 abc 0'"), std::string::npos) << bad;
  // Unsupported versions and binary files.
  const std::string v30 = bad_file_error("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", 2);
  EXPECT_NE(v30.find("3.0"), std::string::npos) << v30;
  EXPECT_NE(v30.find("2.2 and 4.1"), std::string::npos) << v30;
  EXPECT_NE(bad_file_error("$MeshFormat\n4.0 0 8\n$EndMeshFormat\n", 2).find("4.0"), std::string::npos);
  EXPECT_NE(
      bad_file_error("$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n", 2).find("binary .msh not supported"),
      std::string::npos);
  // An element referring to a node that does not exist.
  const std::string nodes = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
  const std::string missing = bad_file_error(kHead22 + nodes + "$Elements\n1\n1 4 2 1 1 1 2 3 44\n$EndElements\n", 13);
  EXPECT_NE(missing.find("44"), std::string::npos) << missing;
  // A flat tet, a wrong node count, a missing $End line, a 4.1 node block that ends early.
  EXPECT_NE(bad_file_error(kHead22 + nodes + "$Elements\n1\n1 4 2 1 1 1 2 3 3\n$EndElements\n", 13).find("degenerate"),
            std::string::npos);
  bad_file_error(kHead22 + nodes + "$Elements\n1\n1 4 2 1 1 1 2 3\n$EndElements\n", 13);
  bad_file_error(kHead22 + nodes + "$Elements\n1\n1 4 2 1 1 1 2 3 4\n$Foo\n", 14);
  bad_file_error("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n3 1 0 2\n1\n2\n0 0 0\n$EndNodes\n", 10);
  // Not a .msh file at all.
  bad_file_error("solid cube\nfacet normal 0 0 1\n", 1);
}

TEST(MshReader, MeshesWithoutTetsAndMissingFilesAreErrors) {
  const fs::path dir = scratch_dir();
  const fs::path path = write_text(dir / "flat.msh", kHead22 +
                                                         "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
                                                         "$Elements\n1\n1 2 2 1 1 1 2 3\n$EndElements\n");
  const std::string flat = error_of([&] { read_msh(path); });
  EXPECT_NE(flat.find("flat.msh"), std::string::npos) << flat;
  EXPECT_NE(flat.find("no 4-node tetrahedra"), std::string::npos) << flat;
  const std::string missing = error_of([&] { read_msh(dir / "nope.msh"); });
  EXPECT_NE(missing.find("nope.msh"), std::string::npos) << missing;
}

}  // namespace
}  // namespace sflsh::fullspace
