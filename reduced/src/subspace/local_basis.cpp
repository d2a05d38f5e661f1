#include <sflsh/core/error.hpp>
#include <sflsh/reduced/local_basis.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace sflsh::reduced {

namespace {

constexpr double kUnreached = std::numeric_limits<double>::infinity();

/// Node adjacency along the tets' edges, with rest lengths [m].
struct EdgeGraph {
  std::vector<int> offset, neighbour;
  std::vector<double> length;
};

EdgeGraph edge_graph(const model::Problem& problem) {
  const int n = problem.num_nodes();
  std::vector<std::vector<int>> adjacent(static_cast<std::size_t>(n));
  for (Eigen::Index e = 0; e < problem.tets.rows(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (a != b) adjacent[static_cast<std::size_t>(problem.tets(e, a))].push_back(problem.tets(e, b));
  EdgeGraph graph;
  graph.offset.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i) {
    auto& list = adjacent[static_cast<std::size_t>(i)];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    graph.offset[static_cast<std::size_t>(i) + 1] =
        graph.offset[static_cast<std::size_t>(i)] + static_cast<int>(list.size());
    for (int j : list) {
      graph.neighbour.push_back(j);
      graph.length.push_back((problem.rest.row(i) - problem.rest.row(j)).norm());
    }
  }
  return graph;
}

/// Shortest paths from `sources` (distance 0) along the edges, up to `cutoff` [m]; kUnreached beyond. Attached nodes
/// are reached but not passed through (a bump does not cross the bone).
void shortest_paths(const EdgeGraph& graph, const std::vector<char>& attached, const std::vector<int>& sources,
                    double cutoff, std::vector<double>& distance, std::vector<int>& touched) {
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (int s : sources) {
    if (distance[static_cast<std::size_t>(s)] == 0.0) continue;
    if (distance[static_cast<std::size_t>(s)] == kUnreached) touched.push_back(s);
    distance[static_cast<std::size_t>(s)] = 0.0;
    queue.emplace(0.0, s);
  }
  while (!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > distance[static_cast<std::size_t>(i)] || attached[static_cast<std::size_t>(i)]) continue;
    for (int k = graph.offset[static_cast<std::size_t>(i)]; k < graph.offset[static_cast<std::size_t>(i) + 1]; ++k) {
      const int j = graph.neighbour[static_cast<std::size_t>(k)];
      const double dj = d + graph.length[static_cast<std::size_t>(k)];
      if (dj >= cutoff || dj >= distance[static_cast<std::size_t>(j)]) continue;
      if (distance[static_cast<std::size_t>(j)] == kUnreached) touched.push_back(j);
      distance[static_cast<std::size_t>(j)] = dj;
      queue.emplace(dj, j);
    }
  }
}

/// Tets with a node in the support, ascending.
std::vector<int> touched_tets(const model::Problem& problem, const std::vector<char>& supported) {
  std::vector<int> tets;
  for (Eigen::Index e = 0; e < problem.tets.rows(); ++e)
    for (int a = 0; a < 4; ++a)
      if (supported[static_cast<std::size_t>(problem.tets(e, a))]) {
        tets.push_back(static_cast<int>(e));
        break;
      }
  return tets;
}

double wendland(double r) { return r >= 1.0 ? 0.0 : std::pow(1.0 - r, 4) * (4.0 * r + 1.0); }

}  // namespace

LocalBasis local_basis(const model::Problem& problem, const std::vector<int>& nodes, const LocalBasisOptions& options) {
  require(options.spacing >= 0.0 && options.radius_factor >= 1.0 && options.depth >= 0.0,
          "local basis: spacing must be ≥ 0 m, radius_factor ≥ 1 and depth ≥ 0 m (got {}, {}, {})", options.spacing,
          options.radius_factor, options.depth);
  const int n = problem.num_nodes();
  LocalBasis basis;
  basis.spacing = options.spacing;
  basis.radius = options.radius_factor * options.spacing;
  basis.functions.resize(n, 0);
  const std::vector<char> mask = problem.dirichlet.mask(n);
  std::vector<char> attached(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) attached[static_cast<std::size_t>(i)] = mask[3 * static_cast<std::size_t>(i)] != 0;
  std::vector<int> sources;
  for (int i : nodes) {
    require(i >= 0 && i < n, "local basis: node {} is not a node of the layer (0…{})", i, n - 1);
    if (!attached[static_cast<std::size_t>(i)]) sources.push_back(i);
  }
  if (sources.empty()) return basis;
  const EdgeGraph graph = edge_graph(problem);

  // The candidates: free nodes within `depth` of the given ones.
  std::vector<double> distance(static_cast<std::size_t>(n), kUnreached);
  std::vector<int> candidates;
  shortest_paths(graph, attached, sources, options.depth + 1e-12, distance, candidates);
  std::erase_if(candidates, [&](int i) { return attached[static_cast<std::size_t>(i)] != 0; });
  std::sort(candidates.begin(), candidates.end());
  if (options.spacing == 0.0) {  // one function per node: the region's nodes are free (a full-space patch)
    basis.radius = 0.0;
    basis.centres = candidates;
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<char> supported(static_cast<std::size_t>(n), 0);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      entries.emplace_back(candidates[k], static_cast<int>(k), 1.0);
      supported[static_cast<std::size_t>(candidates[k])] = 1;
    }
    basis.functions.resize(n, static_cast<Eigen::Index>(candidates.size()));
    basis.functions.setFromTriplets(entries.begin(), entries.end());
    basis.tets = touched_tets(problem, supported);
    return basis;
  }

  // Farthest-point sampling along the edges until every candidate is within h of a centre; started at the lowest
  // candidate index, so the result is deterministic.
  std::vector<double> to_centre(static_cast<std::size_t>(n), kUnreached);
  std::vector<int> touched;
  int next = candidates.front();
  while (true) {
    basis.centres.push_back(next);
    shortest_paths(graph, attached, {next}, kUnreached, to_centre, touched);
    double farthest = -1.0;
    for (int i : candidates)
      if (to_centre[static_cast<std::size_t>(i)] > farthest) {
        farthest = to_centre[static_cast<std::size_t>(i)];
        next = i;
      }
    if (farthest < options.spacing) break;
  }

  // The bumps and the tets they touch.
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<char> supported(static_cast<std::size_t>(n), 0);
  std::vector<double> d(static_cast<std::size_t>(n), kUnreached);
  for (std::size_t k = 0; k < basis.centres.size(); ++k) {
    std::vector<int> reached;
    shortest_paths(graph, attached, {basis.centres[k]}, basis.radius, d, reached);
    for (int i : reached) {
      const double value = wendland(d[static_cast<std::size_t>(i)] / basis.radius);
      if (!attached[static_cast<std::size_t>(i)] && value > 0.0) {
        entries.emplace_back(i, static_cast<int>(k), value);
        supported[static_cast<std::size_t>(i)] = 1;
      }
      d[static_cast<std::size_t>(i)] = kUnreached;
    }
  }
  basis.functions.resize(n, static_cast<Eigen::Index>(basis.centres.size()));
  basis.functions.setFromTriplets(entries.begin(), entries.end());
  basis.tets = touched_tets(problem, supported);
  return basis;
}

Subspace local_subspace(const Subspace& base, const LocalBasis& local) {
  require(local.functions.rows() == base.basis.rows(), "local basis: {} rows for a subspace of {} nodes",
          local.functions.rows(), base.basis.rows());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(base.basis.nonZeros() + local.functions.nonZeros()));
  const auto s = static_cast<int>(base.basis.cols());
  for (Eigen::Index i = 0; i < base.basis.outerSize(); ++i) {
    for (SparseRowMatrix::InnerIterator it(base.basis, i); it; ++it)
      entries.emplace_back(static_cast<int>(i), static_cast<int>(it.col()), it.value());
    for (SparseRowMatrix::InnerIterator it(local.functions, i); it; ++it)
      entries.emplace_back(static_cast<int>(i), s + static_cast<int>(it.col()), it.value());
  }
  Subspace out;
  out.basis.resize(base.basis.rows(), base.basis.cols() + local.functions.cols());
  out.basis.setFromTriplets(entries.begin(), entries.end());
  return out;
}

}  // namespace sflsh::reduced
