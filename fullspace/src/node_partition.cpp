#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/node_partition.hpp>

#include <algorithm>
#include <numeric>

namespace sflsh::fullspace {

namespace {

/// Node adjacency in compressed rows (no self loops, neighbours ascending).
struct Graph {
  std::vector<int> start;  ///< num_nodes + 1 offsets into `neighbour`
  std::vector<int> neighbour;
  int degree(int v) const { return start[static_cast<std::size_t>(v) + 1] - start[static_cast<std::size_t>(v)]; }
};

Graph node_graph(int num_nodes, const meshing::RowMatrixX4i& tets) {
  std::vector<std::vector<int>> lists(static_cast<std::size_t>(num_nodes));
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        if (a != b) lists[static_cast<std::size_t>(tets(e, a))].push_back(tets(e, b));
      }
    }
  }
  Graph g;
  g.start.assign(static_cast<std::size_t>(num_nodes) + 1, 0);
  for (int v = 0; v < num_nodes; ++v) {
    auto& list = lists[static_cast<std::size_t>(v)];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    g.start[static_cast<std::size_t>(v) + 1] = g.start[static_cast<std::size_t>(v)] + static_cast<int>(list.size());
  }
  g.neighbour.reserve(static_cast<std::size_t>(g.start.back()));
  for (const auto& list : lists) g.neighbour.insert(g.neighbour.end(), list.begin(), list.end());
  return g;
}

/// Breadth-first levels from `root` within its component: the visit order and, per visited node, its level.
/// `level` must be −1 on the component on entry and is left set.
std::vector<int> bfs(const Graph& g, int root, std::vector<int>& level) {
  std::vector<int> order{root};
  level[static_cast<std::size_t>(root)] = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int v = order[k];
    for (int j = g.start[static_cast<std::size_t>(v)]; j < g.start[static_cast<std::size_t>(v) + 1]; ++j) {
      const int w = g.neighbour[static_cast<std::size_t>(j)];
      if (level[static_cast<std::size_t>(w)] >= 0) continue;
      level[static_cast<std::size_t>(w)] = level[static_cast<std::size_t>(v)] + 1;
      order.push_back(w);
    }
  }
  return order;
}

/// A node of (nearly) maximal eccentricity in root's component: repeatedly restart from a minimum-degree
/// node of the deepest level while the depth grows (George & Liu 1979).
int pseudo_peripheral(const Graph& g, int root) {
  std::vector<int> level(g.start.size() - 1, -1);
  int depth = -1;
  for (int round = 0; round < 8; ++round) {
    const std::vector<int> order = bfs(g, root, level);
    const int new_depth = level[static_cast<std::size_t>(order.back())];
    int best = order.back();
    for (auto it = order.rbegin(); it != order.rend() && level[static_cast<std::size_t>(*it)] == new_depth; ++it) {
      if (g.degree(*it) < g.degree(best)) best = *it;
    }
    for (int v : order) level[static_cast<std::size_t>(v)] = -1;  // reset only what was touched
    if (new_depth <= depth) break;
    depth = new_depth;
    root = best;
  }
  return root;
}

}  // namespace

std::vector<int> reverse_cuthill_mckee(int num_nodes, const meshing::RowMatrixX4i& tets) {
  require(num_nodes >= 0, "node ordering: negative node count {}", num_nodes);
  require(tets.size() == 0 || (tets.minCoeff() >= 0 && tets.maxCoeff() < num_nodes),
          "node ordering: tet node index out of range [0, {})", num_nodes);
  const Graph g = node_graph(num_nodes, tets);
  std::vector<int> by_degree(static_cast<std::size_t>(num_nodes));
  std::iota(by_degree.begin(), by_degree.end(), 0);
  std::stable_sort(by_degree.begin(), by_degree.end(), [&](int a, int b) { return g.degree(a) < g.degree(b); });

  std::vector<char> placed(static_cast<std::size_t>(num_nodes), 0);
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(num_nodes));
  std::vector<int> isolated;
  std::vector<int> children;
  for (int seed : by_degree) {
    if (placed[static_cast<std::size_t>(seed)]) continue;
    if (g.degree(seed) == 0) {
      isolated.push_back(seed);
      placed[static_cast<std::size_t>(seed)] = 1;
      continue;
    }
    // Cuthill–McKee from a peripheral node: neighbours in increasing degree.
    const int root = pseudo_peripheral(g, seed);
    std::size_t head = order.size();
    order.push_back(root);
    placed[static_cast<std::size_t>(root)] = 1;
    for (; head < order.size(); ++head) {
      const int v = order[head];
      children.clear();
      for (int j = g.start[static_cast<std::size_t>(v)]; j < g.start[static_cast<std::size_t>(v) + 1]; ++j) {
        const int w = g.neighbour[static_cast<std::size_t>(j)];
        if (placed[static_cast<std::size_t>(w)]) continue;
        placed[static_cast<std::size_t>(w)] = 1;
        children.push_back(w);
      }
      std::stable_sort(children.begin(), children.end(), [&](int a, int b) { return g.degree(a) < g.degree(b); });
      order.insert(order.end(), children.begin(), children.end());
    }
  }
  std::reverse(order.begin(), order.end());
  order.insert(order.end(), isolated.begin(), isolated.end());
  return order;
}

NodePartition partition_nodes(int num_nodes, const meshing::RowMatrixX4i& tets, int size) {
  require(size >= 1, "node partition: {} processes", size);
  NodePartition p;
  p.node_of = reverse_cuthill_mckee(num_nodes, tets);
  p.index_of.assign(static_cast<std::size_t>(num_nodes), -1);
  for (int k = 0; k < num_nodes; ++k) p.index_of[static_cast<std::size_t>(p.node_of[static_cast<std::size_t>(k)])] = k;

  // Weight of a node: the tets it is in, plus one so that isolated nodes still count as rows.
  std::vector<long> weight(static_cast<std::size_t>(num_nodes), 1);
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    for (int a = 0; a < 4; ++a) ++weight[static_cast<std::size_t>(tets(e, a))];
  }
  long total = 0;
  for (long w : weight) total += w;
  p.range.assign(static_cast<std::size_t>(size) + 1, num_nodes);
  p.range[0] = 0;
  long cumulative = 0;
  int r = 1;
  for (int k = 0; k < num_nodes && r < size; ++k) {
    // Rank r starts at the first index whose preceding weight reaches r/size of the total.
    while (r < size && cumulative * size >= total * r) p.range[static_cast<std::size_t>(r++)] = k;
    cumulative += weight[static_cast<std::size_t>(p.node_of[static_cast<std::size_t>(k)])];
  }
  return p;
}

}  // namespace sflsh::fullspace
