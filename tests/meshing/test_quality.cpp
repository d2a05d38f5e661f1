// Tet quality measures on tets whose answers are known in closed form.
#include <sflsh/meshing/quality.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>

using namespace sflsh::meshing;

namespace {

RowMatrixX3d points(std::initializer_list<Eigen::RowVector3d> list) {
  RowMatrixX3d out(static_cast<Eigen::Index>(list.size()), 3);
  Eigen::Index i = 0;
  for (const auto& p : list) out.row(i++) = p;
  return out;
}

RowMatrixX4i one_tet(int a, int b, int c, int d) {
  RowMatrixX4i tets(1, 4);
  tets << a, b, c, d;
  return tets;
}

// Alternate corners of the cube [−1, 1]³: a regular tet of edge 2√2, volume 8/3, positively ordered.
RowMatrixX3d regular_nodes() { return points({{1, 1, 1}, {-1, -1, 1}, {-1, 1, -1}, {1, -1, -1}}); }

const double kRegularDihedral = std::acos(1.0 / 3.0) * 180.0 / std::numbers::pi;  // 70.5288°
const double kRegularRadiusEdge = std::sqrt(6.0) / 4.0;                           // 0.6124

}  // namespace

TEST(TetQuality, RegularTetHasTheKnownAnglesRatioAndVolume) {
  const QualityReport q = quality_report(regular_nodes(), one_tet(0, 1, 2, 3));
  EXPECT_EQ(q.tets, 1);
  EXPECT_EQ(q.nodes, 4);
  EXPECT_NEAR(q.min_volume, 8.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.total_volume, 8.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.min_dihedral_deg, kRegularDihedral, 1e-9);
  EXPECT_NEAR(q.median_dihedral_deg, kRegularDihedral, 1e-9);
  EXPECT_NEAR(q.max_dihedral_deg, kRegularDihedral, 1e-9);
  EXPECT_NEAR(q.max_radius_edge, kRegularRadiusEdge, 1e-12);
  EXPECT_EQ(q.inverted, 0);
  EXPECT_EQ(q.degenerate, 0);
  EXPECT_TRUE(q.valid());
}

TEST(TetQuality, CornerTetDihedralsAndRadiusEdge) {
  // The corner tet (0, e1, e2, e3): three right dihedrals at the axes, three of acos(1/√3) = 54.74°
  // at the slanted face; circumcentre (½, ½, ½), R = √3/2, shortest edge 1.
  const RowMatrixX3d nodes = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  const TetQuality per_tet = tet_quality(nodes, one_tet(0, 1, 2, 3));
  EXPECT_NEAR(per_tet.volume(0), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(per_tet.min_dihedral_deg(0), std::acos(1.0 / std::sqrt(3.0)) * 180.0 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(per_tet.radius_edge(0), std::sqrt(3.0) / 2.0, 1e-12);
  const QualityReport q = quality_report(nodes, one_tet(0, 1, 2, 3));
  EXPECT_NEAR(q.max_dihedral_deg, 90.0, 1e-9);
  // Six angles: 54.74° ×3 and 90° ×3; the median (upper middle) is 90°.
  EXPECT_NEAR(q.median_dihedral_deg, 90.0, 1e-9);
}

TEST(TetQuality, InvertedTetIsCountedInvertedButNotDegenerate) {
  const QualityReport q = quality_report(regular_nodes(), one_tet(0, 2, 1, 3));
  EXPECT_NEAR(q.min_volume, -8.0 / 3.0, 1e-12);
  EXPECT_EQ(q.inverted, 1);
  EXPECT_EQ(q.degenerate, 0);
  EXPECT_NEAR(q.min_dihedral_deg, kRegularDihedral, 1e-9);  // angles do not depend on the orientation
  EXPECT_FALSE(q.valid());
}

TEST(TetQuality, FlatTetIsDegenerateAndInverted) {
  const RowMatrixX3d nodes = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}});
  const QualityReport q = quality_report(nodes, one_tet(0, 1, 2, 3));
  EXPECT_EQ(q.min_volume, 0.0);
  EXPECT_EQ(q.inverted, 1);  // volume ≤ 0
  EXPECT_EQ(q.degenerate, 1);
  EXPECT_TRUE(std::isinf(q.max_radius_edge));
  EXPECT_FALSE(q.valid());
}

TEST(TetQuality, NearlyFlatSliverIsDegenerateThoughPositive) {
  // Four nearly coplanar points of a unit square, lifted by 1e-5: positive volume, dihedral ≈ 0.001°.
  const RowMatrixX3d nodes = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1e-5}});
  const TetQuality per_tet = tet_quality(nodes, one_tet(0, 1, 2, 3));
  ASSERT_GT(per_tet.volume(0), 0.0);
  EXPECT_LT(per_tet.min_dihedral_deg(0), 0.1);
  const QualityReport q = quality_report(nodes, one_tet(0, 1, 2, 3));
  EXPECT_EQ(q.inverted, 0);
  EXPECT_EQ(q.degenerate, 1);
}

TEST(TetQuality, CoincidentNodesAreDegenerate) {
  const RowMatrixX3d nodes = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}});
  const QualityReport q = quality_report(nodes, one_tet(0, 1, 2, 3));
  EXPECT_EQ(q.degenerate, 1);
  EXPECT_EQ(q.inverted, 1);
}

TEST(TetQuality, MedianIsOverAllDihedralsOfAllTets) {
  // A regular tet plus the corner tet: twelve angles 54.74 ×3, 70.53 ×6, 90 ×3 → median 70.53.
  RowMatrixX3d nodes(8, 3);
  nodes << regular_nodes(), points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  RowMatrixX4i tets(2, 4);
  tets << 0, 1, 2, 3, 4, 5, 6, 7;
  const QualityReport q = quality_report(nodes, tets);
  EXPECT_NEAR(q.median_dihedral_deg, kRegularDihedral, 1e-9);
  EXPECT_NEAR(q.total_volume, 8.0 / 3.0 + 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(q.min_volume, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(q.max_radius_edge, std::sqrt(3.0) / 2.0, 1e-12);
}

TEST(TetQuality, EmptyMeshIsNotValid) {
  const QualityReport q = quality_report(RowMatrixX3d(0, 3), RowMatrixX4i(0, 4));
  EXPECT_EQ(q.tets, 0);
  EXPECT_FALSE(q.valid());
  EXPECT_EQ(tet_quality(RowMatrixX3d(0, 3), RowMatrixX4i(0, 4)).volume.size(), 0);
}

TEST(TetQuality, JsonCarriesEveryField) {
  QualityReport q = quality_report(regular_nodes(), one_tet(0, 1, 2, 3));
  q.thickness_median = 0.03;
  nlohmann::json json;
  to_json(json, q);
  EXPECT_EQ(json["tets"].get<long>(), 1);
  EXPECT_EQ(json["nodes"].get<long>(), 4);
  EXPECT_NEAR(json["min_dihedral_deg"].get<double>(), kRegularDihedral, 1e-9);
  EXPECT_NEAR(json["median_dihedral_deg"].get<double>(), kRegularDihedral, 1e-9);
  EXPECT_NEAR(json["max_dihedral_deg"].get<double>(), kRegularDihedral, 1e-9);
  EXPECT_NEAR(json["max_radius_edge"].get<double>(), kRegularRadiusEdge, 1e-12);
  EXPECT_NEAR(json["min_volume_m3"].get<double>(), 8.0 / 3.0, 1e-12);
  EXPECT_NEAR(json["total_volume_m3"].get<double>(), 8.0 / 3.0, 1e-12);
  EXPECT_EQ(json["inverted"].get<long>(), 0);
  EXPECT_EQ(json["degenerate"].get<long>(), 0);
  EXPECT_EQ(json["thickness_min_m"].get<double>(), 0.0);
  EXPECT_EQ(json["thickness_median_m"].get<double>(), 0.03);
  EXPECT_EQ(json["thickness_max_m"].get<double>(), 0.0);
  EXPECT_TRUE(json["valid"].get<bool>());
  // The json conversion is found by ADL, so reports also convert implicitly.
  const nlohmann::json implicit = q;
  EXPECT_EQ(implicit, json);
}

TEST(PartNames, EveryPartHasItsName) {
  EXPECT_STREQ(part_name(Part::torso), "torso");
  EXPECT_STREQ(part_name(Part::left_upper_arm), "left_upper_arm");
  EXPECT_STREQ(part_name(Part::right_upper_arm), "right_upper_arm");
  EXPECT_STREQ(part_name(Part::left_thigh), "left_thigh");
  EXPECT_STREQ(part_name(Part::right_thigh), "right_thigh");
}
