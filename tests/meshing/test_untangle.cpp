// Local untangling (meshing/untangle.hpp) on a structured block whose interior nodes are scrambled.
#include <sflsh/meshing/quality.hpp>
#include <sflsh/meshing/untangle.hpp>

#include <gtest/gtest.h>

#include <random>

namespace sflsh::meshing {
namespace {

struct Block {
  RowMatrixX3d nodes;
  RowMatrixX4i tets;
  std::vector<char> fixed;  ///< the block's surface nodes
};

// n × n × n unit cubes of edge 1 cm, six positive tets each (Kuhn subdivision along the main diagonal).
Block kuhn_block(int n) {
  Block block;
  const int m = n + 1;
  const auto index = [m](int i, int j, int k) { return (k * m + j) * m + i; };
  block.nodes.resize(m * m * m, 3);
  block.fixed.assign(static_cast<std::size_t>(m * m * m), 0);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        block.nodes.row(index(i, j, k)) << 0.01 * i, 0.01 * j, 0.01 * k;
        block.fixed[static_cast<std::size_t>(index(i, j, k))] =
            (i == 0 || j == 0 || k == 0 || i == n || j == n || k == n) ? 1 : 0;
      }
  // The six paths from corner 0 to corner 7 of a cube, one tet each.
  const int paths[6][3] = {{1, 3, 7}, {1, 5, 7}, {2, 3, 7}, {2, 6, 7}, {4, 5, 7}, {4, 6, 7}};
  std::vector<Eigen::RowVector4i> tets;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto corner = [&](int bits) {
          return index(i + (bits & 1), j + ((bits >> 1) & 1), k + ((bits >> 2) & 1));
        };
        for (const auto& path : paths) tets.emplace_back(corner(0), corner(path[0]), corner(path[1]), corner(7));
      }
  block.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (std::size_t e = 0; e < tets.size(); ++e) {
    block.tets.row(static_cast<Eigen::Index>(e)) = tets[e];
    if (signed_volume(block.nodes, block.tets, static_cast<Eigen::Index>(e)) < 0.0)
      std::swap(block.tets(static_cast<Eigen::Index>(e), 1), block.tets(static_cast<Eigen::Index>(e), 2));
  }
  return block;
}

long inverted(const Block& block) {
  long count = 0;
  for (Eigen::Index e = 0; e < block.tets.rows(); ++e) count += signed_volume(block.nodes, block.tets, e) <= 0.0;
  return count;
}

TEST(Untangle, KuhnBlockIsValidAndNeedsNothing) {
  Block block = kuhn_block(4);
  EXPECT_EQ(inverted(block), 0);
  const RowMatrixX3d before = block.nodes;
  EXPECT_EQ(untangle(block.nodes, block.tets, block.fixed), 0);
  EXPECT_EQ(block.nodes, before);
}

TEST(Untangle, ScrambledInteriorNodesComeBackValidWithTheBoundaryUntouched) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Block block = kuhn_block(4);
    const RowMatrixX3d boundary = block.nodes;
    // Every interior node displaced by up to 1.2 cells per coordinate: dozens of tets inverted, many of them with
    // several free corners. Untangled means valid: no tet inverted or degenerate (quality.hpp's thresholds).
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> offset(-0.012, 0.012);
    for (Eigen::Index i = 0; i < block.nodes.rows(); ++i)
      if (!block.fixed[static_cast<std::size_t>(i)])
        for (int c = 0; c < 3; ++c) block.nodes(i, c) += offset(random);
    ASSERT_GT(inverted(block), 20);
    EXPECT_GT(untangle(block.nodes, block.tets, block.fixed), 0);
    EXPECT_EQ(inverted(block), 0);
    const QualityReport report = quality_report(block.nodes, block.tets);
    EXPECT_TRUE(report.valid()) << report.degenerate << " degenerate, min dihedral " << report.min_dihedral_deg;
    // The block's volume is the boundary's: valid tets tile it exactly (round-off of 384 determinants).
    EXPECT_NEAR(report.total_volume, 64e-6, 1e-15);
    for (Eigen::Index i = 0; i < block.nodes.rows(); ++i) {
      if (block.fixed[static_cast<std::size_t>(i)]) {
        EXPECT_EQ(block.nodes.row(i), boundary.row(i)) << "node " << i;
      }
    }
  }
}

TEST(Untangle, TetsWithFourFixedNodesAreLeftForTheCallerToReport) {
  Block block = kuhn_block(1);                // one cube: every node on the boundary
  block.nodes.row(7) << -0.01, -0.01, -0.01;  // corner 7 through corner 0 inverts every tet
  ASSERT_GT(inverted(block), 0);
  const RowMatrixX3d before = block.nodes;
  EXPECT_EQ(untangle(block.nodes, block.tets, block.fixed), 0);
  EXPECT_EQ(block.nodes, before);
  EXPECT_GT(inverted(block), 0);
}

}  // namespace
}  // namespace sflsh::meshing
