// Farthest-point sampling of the material control points; see control_points.hpp for the properties.
#include <sflsh/core/error.hpp>
#include <sflsh/material/control_points.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

namespace sflsh::material {

namespace {

void check_options(const ControlPointOptions& options, Eigen::Index n) {
  const auto& density = options.density;
  if (density.size() > 0) {
    require(density.size() == n, "control points: density has {} entries for {} vertices", density.size(), n);
    for (Eigen::Index v = 0; v < n; ++v)
      require(std::isfinite(density(v)) && density(v) > 0.0,
              "control points: density at vertex {} is {} (must be finite and > 0)", v, density(v));
  }
  if (!options.part.empty()) {
    require(static_cast<Eigen::Index>(options.part.size()) == n, "control points: part has {} entries for {} vertices",
            options.part.size(), n);
    for (std::size_t v = 0; v < options.part.size(); ++v)
      require(options.part[v] >= 0, "control points: part id of vertex {} is {} (must be ≥ 0)", v, options.part[v]);
  }
  if (!options.mirror.empty()) {
    require(static_cast<Eigen::Index>(options.mirror.size()) == n,
            "control points: mirror map has {} entries for {} vertices", options.mirror.size(), n);
    for (std::size_t v = 0; v < options.mirror.size(); ++v) {
      const int m = options.mirror[v];
      require(m >= -1 && m < n, "control points: mirror of vertex {} is {} (must be −1 or in [0, {}))", v, m, n);
    }
  }
}

// The sampler's state: the distance of every vertex to the chosen set, and which parts hold a point.
class Sampler {
 public:
  Sampler(const RowMatrixX3d& V, const RowMatrixX3i& F, const ControlPointOptions& options)
      : V_(V), options_(options), adjacency_(vertex_adjacency(F, static_cast<int>(V.rows()))) {
    distance_ = Eigen::VectorXd::Constant(V.rows(), std::numeric_limits<double>::infinity());
    const auto n = static_cast<std::size_t>(V.rows());
    part_.assign(n, 0);
    if (!options.part.empty()) part_ = options.part;
    for (const int p : part_) part_count_[p] = 0;
    if (!options.mirror.empty()) {
      plane_.assign(n, 0);
      for (std::size_t v = 0; v < n; ++v) plane_[v] = is_plane_vertex(adjacency_, options.mirror, static_cast<int>(v));
    }
  }

  const std::vector<int>& chosen() const { return chosen_; }

  // The first point: nearest to the density²-weighted centroid among the vertices of the heaviest part
  // (restricted to plane vertices when there is a mirror map and that part has some).
  int seed(const RowMatrixX3i& F) const {
    const Eigen::VectorXd mass = lumped_mass(V_, F);
    Eigen::VectorXd weight = mass;
    if (options_.density.size() > 0) weight = weight.cwiseProduct(options_.density.cwiseAbs2());
    const Eigen::RowVector3d centroid = (V_.array().colwise() * weight.array()).colwise().sum() / weight.sum();
    std::map<int, double> part_weight;
    for (std::size_t v = 0; v < part_.size(); ++v) part_weight[part_[v]] += weight(static_cast<Eigen::Index>(v));
    int heaviest = part_weight.begin()->first;
    for (const auto& [p, w] : part_weight)
      if (w > part_weight[heaviest]) heaviest = p;
    bool part_has_plane = false;
    for (std::size_t v = 0; v < part_.size() && !plane_.empty(); ++v)
      part_has_plane = part_has_plane || (part_[v] == heaviest && plane_[v]);
    int best = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < part_.size(); ++v) {
      if (part_[v] != heaviest || (part_has_plane && !plane_[v])) continue;
      const double d = (V_.row(static_cast<Eigen::Index>(v)) - centroid).squaredNorm();
      if (d < best_distance) best = static_cast<int>(v), best_distance = d;  // strict <: smallest index wins ties
    }
    return best;
  }

  // The farthest vertex among the candidates: the plane vertices when `plane_only` (they complete a
  // symmetric group, so part coverage does not apply), else the vertices of the parts without a point
  // while there are any, else all. nullopt when no candidate is at a positive distance.
  std::optional<int> farthest(bool plane_only) const {
    const bool uncovered = !plane_only && std::any_of(part_count_.begin(), part_count_.end(),
                                                      [](const auto& pc) { return pc.second == 0; });
    int best = -1;
    double best_distance = 0.0;
    for (Eigen::Index v = 0; v < distance_.size(); ++v) {
      const auto i = static_cast<std::size_t>(v);
      if (uncovered && part_count_.at(part_[i]) > 0) continue;
      if (plane_only && !plane_[i]) continue;
      if (distance_(v) > best_distance) best = static_cast<int>(v), best_distance = distance_(v);
    }
    if (best < 0) return std::nullopt;
    return best;
  }

  void add(int v) {
    relax_edge_distances(V_, adjacency_, v, options_.density, distance_);
    ++part_count_[part_[static_cast<std::size_t>(v)]];
    chosen_.push_back(v);
  }

  // One group of points (see control_points.hpp): a mirror pair, two plane vertices, or a single vertex.
  void add_group() {
    const std::optional<int> next = farthest(false);
    require(next.has_value(), "control points: every vertex already holds a control point");
    const int v = *next;
    if (plane_.empty() || options_.mirror[static_cast<std::size_t>(v)] < 0) {
      add(v);
      return;
    }
    const int m = options_.mirror[static_cast<std::size_t>(v)];
    if (!plane_[static_cast<std::size_t>(v)]) {
      // A pair when the mirror stays far from v once v is in (≥ half the current sampling radius);
      // otherwise v is close to the plane and a plane vertex serves better.
      const double radius = distance_(v);
      Eigen::VectorXd trial = distance_;
      relax_edge_distances(V_, adjacency_, v, options_.density, trial);
      if (trial(m) >= 0.5 * radius) {
        add(v);
        add(m);
        return;
      }
    }
    const std::optional<int> first = farthest(true);
    if (!first) {
      add(v);
      return;
    }
    add(*first);
    if (const std::optional<int> second = farthest(true)) add(*second);
  }

 private:
  const RowMatrixX3d& V_;
  const ControlPointOptions& options_;
  VertexAdjacency adjacency_;
  Eigen::VectorXd distance_;
  std::vector<int> part_;
  std::map<int, int> part_count_;  ///< part id → number of points in it
  std::vector<char> plane_;        ///< per vertex, when there is a mirror map
  std::vector<int> chosen_;
};

}  // namespace

bool is_plane_vertex(const VertexAdjacency& adjacency, const std::vector<int>& mirror, int v) {
  const int m = mirror[static_cast<std::size_t>(v)];
  if (m < 0) return false;
  if (m == v) return true;
  const auto neighbours = adjacency.of(v);
  return std::binary_search(neighbours.begin(), neighbours.end(), m);
}

std::vector<int> place_control_points(const RowMatrixX3d& V, const RowMatrixX3i& F, int count,
                                      const ControlPointOptions& options) {
  validate_surface(V, F);
  require(count >= 1 && count <= V.rows(), "control points: N = {} is not in [1, {}] (the surface's vertex count)",
          count, V.rows());
  check_options(options, V.rows());
  Sampler sampler(V, F, options);
  const int seed = sampler.seed(F);
  sampler.add(seed);
  // The seed starts a plane group when it is a plane vertex: its partner is the farthest plane vertex.
  if (!options.mirror.empty() && is_plane_vertex(vertex_adjacency(F, static_cast<int>(V.rows())), options.mirror, seed))
    if (const std::optional<int> partner = sampler.farthest(true)) sampler.add(*partner);
  while (static_cast<int>(sampler.chosen().size()) < count) sampler.add_group();
  std::vector<int> points = sampler.chosen();
  points.resize(static_cast<std::size_t>(count));  // the sequence never depends on count: nesting holds
  return points;
}

}  // namespace sflsh::material
