// The closed boundary of the soft-tissue layer (docs/architecture.md §3).
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/layer_surface.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::meshing {
namespace {

SurfaceAnchor vertex_anchor(int region_vertex, double depth) {
  SurfaceAnchor anchor;
  anchor.vertex = {region_vertex, region_vertex, region_vertex};
  anchor.weight = Eigen::Vector3d(1.0, 0.0, 0.0);
  anchor.depth = depth;
  return anchor;
}

}  // namespace

LayerSurface build_layer_surface(const Region& region, const LayerGeometry& geometry, double edge_length,
                                 int side_layers) {
  const int count = region.num_vertices();
  require(geometry.skin.rows() == count, "layer surface: geometry has {} skin points for {} region vertices",
          geometry.skin.rows(), count);
  require(!region.boundary_loops.empty(),
          "layer surface: the region has no boundary curve (a closed region has no layer side)");
  if (side_layers <= 0) {
    double longest = 0.0;
    for (const auto& loop : region.boundary_loops)
      for (int v : loop)
        longest = std::max(longest, geometry.thickness(v) * (geometry.skeleton.row(v) - geometry.skin.row(v)).norm());
    side_layers = std::max(1, static_cast<int>(std::ceil(longest / std::max(edge_length, 1e-6) - 0.25)));
  }

  LayerSurface layer;
  layer.side_layers = side_layers;
  std::vector<Eigen::Vector3d> points;
  std::vector<SurfaceAnchor>& anchors = layer.anchors;
  for (int depth_index : {0, 1})
    for (int v = 0; v < count; ++v) anchors.push_back(vertex_anchor(v, depth_index));
  // Side-wall vertices: for every boundary vertex, side_layers − 1 intermediate depths.
  std::vector<int> side_start(count, -1);
  for (const auto& loop : region.boundary_loops)
    for (int v : loop) {
      side_start[v] = static_cast<int>(anchors.size());
      for (int l = 1; l < side_layers; ++l) anchors.push_back(vertex_anchor(v, static_cast<double>(l) / side_layers));
    }
  // Vertex index of boundary vertex v at depth layer l (0 = skin, side_layers = inner).
  const auto at = [&](int v, int l) {
    if (l == 0) return v;
    if (l == side_layers) return count + v;
    return side_start[v] + l - 1;
  };

  auto& surface = layer.surface;
  surface.vertices.resize(static_cast<Eigen::Index>(anchors.size()), 3);
  for (std::size_t i = 0; i < anchors.size(); ++i)
    surface.vertices.row(static_cast<Eigen::Index>(i)) = geometry.position(anchors[i]).transpose();

  std::vector<Eigen::Vector3i> triangles;
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f) {
    triangles.emplace_back(region.faces(f, 0), region.faces(f, 1), region.faces(f, 2));
    surface.patch.push_back(NodeKind::outer);
  }
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f) {  // reversed: the layer's outside is the bone side
    triangles.emplace_back(count + region.faces(f, 0), count + region.faces(f, 2), count + region.faces(f, 1));
    surface.patch.push_back(NodeKind::inner);
  }
  for (const auto& loop : region.boundary_loops) {
    // The skin face uses edge a → b; the side wall uses it as b → a at depth 0, a → b at the inner rim.
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const int a = loop[k], b = loop[(k + 1) % loop.size()];
      for (int l = 0; l < side_layers; ++l) {
        triangles.emplace_back(at(b, l), at(a, l), at(a, l + 1));
        triangles.emplace_back(at(b, l), at(a, l + 1), at(b, l + 1));
        surface.patch.push_back(NodeKind::side);
        surface.patch.push_back(NodeKind::side);
      }
    }
    std::vector<Eigen::Vector3d> outer_rim, inner_rim;
    for (int v : loop) {
      outer_rim.push_back(surface.vertices.row(at(v, 0)).transpose());
      inner_rim.push_back(surface.vertices.row(at(v, side_layers)).transpose());
    }
    outer_rim.push_back(outer_rim.front());
    inner_rim.push_back(inner_rim.front());
    surface.features.push_back(std::move(outer_rim));
    surface.features.push_back(std::move(inner_rim));
  }
  surface.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    surface.triangles.row(static_cast<Eigen::Index>(t)) = triangles[t].transpose();
  return layer;
}

}  // namespace sflsh::meshing
