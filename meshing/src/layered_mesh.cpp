// Extruded layer mesh: prisms along the skeleton columns, split into tets (Dompierre, Labbé, Vallet,
// Camarero 1999, "How to subdivide pyramids, prisms and hexahedra into tetrahedra").
#include "layered_mesh.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <array>

namespace sflsh::meshing::detail {
namespace {

// Rotations/reflections of a prism (top 0,1,2 above bottom 3,4,5) that bring vertex k to position 0.
constexpr int kRotation[6][6] = {{0, 1, 2, 3, 4, 5}, {1, 2, 0, 4, 5, 3}, {2, 0, 1, 5, 3, 4},
                                 {3, 5, 4, 0, 2, 1}, {4, 3, 5, 1, 0, 2}, {5, 4, 3, 2, 1, 0}};

}  // namespace

int layered_layers(SizePreset size) {
  switch (size) {
    case SizePreset::coarse:
      return 1;
    case SizePreset::medium:
      return 2;
    case SizePreset::fine:
      return 8;
  }
  return 2;
}

void build_layered(LayerMesh& mesh, const LayerGeometry& geometry, int layers) {
  require(layers >= 1, "layered mesh: {} layers; expected at least 1", layers);
  const Region& region = mesh.region_surface;
  const int count = region.num_vertices();
  const int n = count * (layers + 1);
  std::vector<char> on_loop(static_cast<std::size_t>(count), 0);
  for (const auto& loop : region.boundary_loops)
    for (int v : loop) on_loop[static_cast<std::size_t>(v)] = 1;

  mesh.nodes.resize(n, 3);
  mesh.kind.assign(static_cast<std::size_t>(n), NodeKind::interior);
  mesh.anchor.assign(static_cast<std::size_t>(n), SurfaceAnchor{});
  for (int l = 0; l <= layers; ++l)
    for (int v = 0; v < count; ++v) {
      const int node = l * count + v;
      SurfaceAnchor& anchor = mesh.anchor[static_cast<std::size_t>(node)];
      anchor.vertex = {v, v, v};
      anchor.weight = Eigen::Vector3d(1.0, 0.0, 0.0);
      anchor.depth = static_cast<double>(l) / layers;
      mesh.kind[static_cast<std::size_t>(node)] = l == 0                                 ? NodeKind::outer
                                                  : l == layers                          ? NodeKind::inner
                                                  : on_loop[static_cast<std::size_t>(v)] ? NodeKind::side
                                                                                         : NodeKind::interior;
      mesh.nodes.row(node) = geometry.position(anchor).transpose();
    }

  std::vector<Eigen::Vector4i> tets;
  tets.reserve(static_cast<std::size_t>(region.faces.rows()) * 3 * static_cast<std::size_t>(layers));
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f)
    for (int l = 0; l < layers; ++l) {
      std::array<int, 6> prism{};
      for (int k = 0; k < 3; ++k) {
        prism[static_cast<std::size_t>(k)] = l * count + region.faces(f, k);
        prism[static_cast<std::size_t>(k + 3)] = (l + 1) * count + region.faces(f, k);
      }
      const int smallest = static_cast<int>(std::min_element(prism.begin(), prism.end()) - prism.begin());
      std::array<int, 6> v{};
      for (int k = 0; k < 6; ++k)
        v[static_cast<std::size_t>(k)] = prism[static_cast<std::size_t>(kRotation[smallest][k])];
      // Split the quad faces through the diagonal from their smallest vertex (conforming with neighbours).
      if (std::min(v[1], v[5]) < std::min(v[2], v[4])) {
        tets.emplace_back(v[0], v[1], v[2], v[5]);
        tets.emplace_back(v[0], v[1], v[5], v[4]);
      } else {
        tets.emplace_back(v[0], v[1], v[2], v[4]);
        tets.emplace_back(v[0], v[4], v[2], v[5]);
      }
      tets.emplace_back(v[0], v[4], v[5], v[3]);
    }
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (std::size_t e = 0; e < tets.size(); ++e) {
    Eigen::Vector4i t = tets[e];
    Eigen::Matrix3d dm;
    for (int k = 0; k < 3; ++k) dm.col(k) = (mesh.nodes.row(t(k + 1)) - mesh.nodes.row(t(0))).transpose();
    const double det = dm.determinant();
    if (det < 0.0) std::swap(t(2), t(3));  // the split's own orientation depends on the rotation
    require(det != 0.0, "layered mesh: tet {} of the template is flat", e);
    mesh.tets.row(static_cast<Eigen::Index>(e)) = t.transpose();
  }

  mesh.skin.node.resize(static_cast<std::size_t>(count));
  mesh.skin.tet.assign(static_cast<std::size_t>(count), -1);
  mesh.skin.bary.assign(static_cast<std::size_t>(count), Eigen::Vector4d::Zero());
  for (int v = 0; v < count; ++v) mesh.skin.node[static_cast<std::size_t>(v)] = v;
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (int c = 0; c < 4; ++c) {
      const int node = mesh.tets(e, c);
      if (node < count && mesh.skin.tet[static_cast<std::size_t>(node)] < 0) {
        mesh.skin.tet[static_cast<std::size_t>(node)] = static_cast<int>(e);
        mesh.skin.bary[static_cast<std::size_t>(node)] = Eigen::Vector4d::Unit(c);
      }
    }
}

}  // namespace sflsh::meshing::detail
