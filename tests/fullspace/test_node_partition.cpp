// The node order and split of the distributed solver: a valid permutation, a narrow band, and on a
// thin layer numbered layer by layer (as the layered mesher does) a cut across the thickness with balanced
// work instead of one along a layer.
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/node_partition.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

namespace sflsh::fullspace {
namespace {

bool is_permutation_of_nodes(const std::vector<int>& order, int n) {
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> expected(static_cast<std::size_t>(n));
  std::iota(expected.begin(), expected.end(), 0);
  return sorted == expected;
}

/// Largest |index(a) − index(b)| over node pairs sharing a tet.
int bandwidth(const meshing::RowMatrixX4i& tets, const std::vector<int>& index_of) {
  int width = 0;
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        width = std::max(width, std::abs(index_of[static_cast<std::size_t>(tets(e, a))] -
                                         index_of[static_cast<std::size_t>(tets(e, b))]));
      }
    }
  }
  return width;
}

TEST(NodePartition, ReverseCuthillMcKeeIsAPermutationWithANarrowBand) {
  // A long bar, 3 × 3 nodes in cross-section and 41 along z, renumbered with z fastest: its band is then
  // several columns of 41 wide, and RCM must find the one across the bar (a few cross-sections).
  const MshMesh mesh = box_tet_mesh({0.1, 0.1, 2.0}, {2, 2, 40});
  const int n = static_cast<int>(mesh.nodes.rows());
  std::vector<int> transposed(static_cast<std::size_t>(n));  // node (i, j, k) → k + 41 (i + 3 j): z fastest
  for (int v = 0; v < n; ++v) {
    const int i = v % 3, j = (v / 3) % 3, k = v / 9;
    transposed[static_cast<std::size_t>(v)] = k + 41 * (i + 3 * j);
  }
  meshing::RowMatrixX4i tets = mesh.tets;
  for (Eigen::Index e = 0; e < tets.rows(); ++e)
    for (int a = 0; a < 4; ++a) tets(e, a) = transposed[static_cast<std::size_t>(tets(e, a))];
  std::vector<int> identity(static_cast<std::size_t>(n));
  std::iota(identity.begin(), identity.end(), 0);
  ASSERT_GT(bandwidth(tets, identity), 41 * 3);

  const std::vector<int> order = reverse_cuthill_mckee(n, tets);
  ASSERT_TRUE(is_permutation_of_nodes(order, n));
  std::vector<int> index_of(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) index_of[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
  EXPECT_LE(bandwidth(tets, index_of), 2 * 9);  // two cross-section planes of 3 × 3 nodes
}

TEST(NodePartition, HandlesComponentsAndNodesInNoTet) {
  meshing::RowMatrixX4i tets(2, 4);
  tets << 0, 1, 2, 3, 5, 6, 7, 8;  // two separate tets; node 4 and 9 belong to none
  const std::vector<int> order = reverse_cuthill_mckee(10, tets);
  ASSERT_TRUE(is_permutation_of_nodes(order, 10));
  EXPECT_TRUE((order[8] == 4 && order[9] == 9) || (order[8] == 9 && order[9] == 4));

  const NodePartition p = partition_nodes(10, tets, 3);
  ASSERT_EQ(p.range.size(), 4u);
  EXPECT_EQ(p.range.front(), 0);
  EXPECT_EQ(p.range.back(), 10);
  EXPECT_TRUE(std::is_sorted(p.range.begin(), p.range.end()));
  for (int v = 0; v < 10; ++v)
    EXPECT_EQ(p.node_of[static_cast<std::size_t>(p.index_of[static_cast<std::size_t>(v)])], v);
}

TEST(NodePartition, ThinLayerNumberedByLayersIsCutAcrossItsThickness) {
  // 24 × 24 cells in the plane, 2 through the thickness, numbered plane by plane (z slowest).
  const MshMesh mesh = box_tet_mesh({1.0, 1.0, 0.05}, {24, 24, 2});
  const int n = static_cast<int>(mesh.nodes.rows());
  const NodePartition p = partition_nodes(n, mesh.tets, 2);
  ASSERT_TRUE(is_permutation_of_nodes(p.node_of, n));

  auto rank_of = [&](int node) { return p.index_of[static_cast<std::size_t>(node)] < p.range[1] ? 0 : 1; };
  int straddling = 0;
  std::array<long, 2> incident{0, 0};
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    bool mixed = false;
    for (int a = 0; a < 4; ++a) {
      ++incident[static_cast<std::size_t>(rank_of(mesh.tets(e, a)))];
      mixed = mixed || rank_of(mesh.tets(e, a)) != rank_of(mesh.tets(e, 0));
    }
    straddling += mixed ? 1 : 0;
  }
  // Cutting the natural numbering in half splits along the middle plane: every tet touching it straddles
  // (all of them here). Across the thickness only a strip of a few cells' width does.
  const auto tets = static_cast<double>(mesh.tets.rows());
  EXPECT_LT(straddling, 0.08 * tets) << straddling << " of " << tets << " tets straddle the cut";
  const double imbalance =
      std::abs(static_cast<double>(incident[0] - incident[1])) / static_cast<double>(incident[0] + incident[1]);
  EXPECT_LT(imbalance, 0.02);
}

}  // namespace
}  // namespace sflsh::fullspace
