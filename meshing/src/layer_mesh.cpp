// Building the template layer mesh: region → correspondence → closed layer boundary → tets → node
// kinds, anchors, parts and the skin embedding (docs/architecture.md §3).
#include "layered_mesh.hpp"
#include "skin_embedding.hpp"

#include <sflsh/body/surface_checks.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/meshing/harmonic.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/meshing/layer_surface.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

namespace sflsh::meshing {
namespace {

// The anchor of a point on a layer-surface triangle: the barycentric blend of its corners' anchors,
// merged per region vertex (side triangles touch two region vertices, skin/inner triangles three).
SurfaceAnchor blend_anchor(const LayerSurface& layer, int triangle, const Eigen::Vector3d& bary) {
  SurfaceAnchor anchor;
  int used = 0;
  anchor.depth = 0.0;
  for (int k = 0; k < 3; ++k) {
    const SurfaceAnchor& corner = layer.anchors[static_cast<std::size_t>(layer.surface.triangles(triangle, k))];
    const int v = corner.vertex[0];
    anchor.depth += bary(k) * corner.depth;
    int slot = -1;
    for (int s = 0; s < used; ++s)
      if (anchor.vertex[s] == v) slot = s;
    if (slot < 0) {
      slot = used++;
      anchor.vertex[slot] = v;
    }
    anchor.weight(slot) += bary(k);
  }
  for (int s = used; s < 3; ++s) anchor.vertex[s] = anchor.vertex[0];
  return anchor;
}

}  // namespace

SizePreset parse_size_preset(const std::string& name) {
  if (name == "coarse") return SizePreset::coarse;
  if (name == "default" || name == "medium") return SizePreset::medium;
  if (name == "fine") return SizePreset::fine;
  throw_error("size: unknown preset '{}' (expected coarse, default or fine)", name);
}

const char* size_preset_name(SizePreset preset) {
  switch (preset) {
    case SizePreset::coarse:
      return "coarse";
    case SizePreset::medium:
      return "default";
    case SizePreset::fine:
      return "fine";
  }
  return "default";
}

long target_tets(SizePreset preset) {
  switch (preset) {
    case SizePreset::coarse:
      return 10'000;
    case SizePreset::medium:
      return 50'000;
    case SizePreset::fine:
      return 200'000;
  }
  return 50'000;
}

std::vector<int> LayerMesh::nodes_of_kind(NodeKind wanted) const {
  std::vector<int> list;
  for (int i = 0; i < num_nodes(); ++i)
    if (kind[static_cast<std::size_t>(i)] == wanted) list.push_back(i);
  return list;
}

std::vector<int> LayerMesh::rim_nodes() const {
  std::vector<char> on_boundary(static_cast<std::size_t>(region_surface.num_vertices()), 0);
  for (const auto& loop : region_surface.boundary_loops)
    for (int v : loop) on_boundary[static_cast<std::size_t>(v)] = 1;
  constexpr double kOffRim = 1e-6;  // anchor weight allowed on vertices off the boundary curves (round-off)
  std::vector<int> list;
  for (int i = 0; i < num_nodes(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (kind[k] != NodeKind::outer) continue;
    double off_rim = 0.0;  // Σ_k w_k over anchor vertices not on a boundary curve
    for (int s = 0; s < 3; ++s)
      if (!on_boundary[static_cast<std::size_t>(anchor[k].vertex[static_cast<std::size_t>(s)])])
        off_rim += std::abs(anchor[k].weight(s));
    if (off_rim <= kOffRim) list.push_back(i);
  }
  return list;
}

Eigen::VectorXd LayerMesh::template_thickness_field() const {
  return Eigen::VectorXd::Constant(region_surface.num_vertices(), template_thickness);
}

RowMatrixX3d LayerMesh::skin_positions(const RowMatrixX3d& node_positions) const {
  const int count = region_surface.num_vertices();
  RowMatrixX3d skin_points(count, 3);
  for (int i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (skin.node[k] >= 0) {
      skin_points.row(i) = node_positions.row(skin.node[k]);
      continue;
    }
    skin_points.row(i).setZero();
    for (int c = 0; c < 4; ++c) skin_points.row(i) += skin.bary[k](c) * node_positions.row(tets(skin.tet[k], c));
  }
  return skin_points;
}

QualityReport layer_quality(const LayerMesh& mesh, const RowMatrixX3d& nodes, const LayerGeometry& geometry) {
  QualityReport report = quality_report(nodes, mesh.tets);
  Eigen::VectorXd thickness = geometry.thickness.cwiseProduct(geometry.max_thickness());
  std::sort(thickness.data(), thickness.data() + thickness.size());
  if (thickness.size() > 0) {
    report.thickness_min = thickness(0);
    report.thickness_median = thickness(thickness.size() / 2);
    report.thickness_max = thickness(thickness.size() - 1);
  }
  return report;
}

int layered_prism_layers(const LayerMeshOptions& options) {
  require(options.layers >= 0 && options.layers <= 64,
          "layered mesh: {} prism layers; expected 1 to 64 (0: the size "
          "preset's)",
          options.layers);
  return options.layers > 0 ? options.layers : detail::layered_layers(options.size);
}

namespace {

/// Throws when the closed boundary of the layer (skin, inner surface, side wall) is not a valid surface.
void check_layer_boundary(const LayerMesh& mesh, const LayerSurface& layer) {
  const auto check = body::check_surface(layer.surface.vertices, layer.surface.triangles, true);
  require(check.ok(), "layer '{}' at h = {}: the closed layer boundary is not a valid surface ({})", mesh.region,
          mesh.template_thickness, check.summary());
}

/// The layered mesher's mesh: prisms on the skin triangles, parts from each node's skin vertex, tets by majority.
void build_layered_layer(LayerMesh& mesh, const LayerGeometry& geometry, const LayerMeshOptions& options) {
  const Region& region = mesh.region_surface;
  check_layer_boundary(mesh, build_layer_surface(region, geometry, 1.0, 1));
  detail::build_layered(mesh, geometry, layered_prism_layers(options));
  mesh.node_part.resize(static_cast<std::size_t>(mesh.num_nodes()));
  for (int i = 0; i < mesh.num_nodes(); ++i)
    mesh.node_part[static_cast<std::size_t>(i)] =
        region.part[static_cast<std::size_t>(mesh.anchor[static_cast<std::size_t>(i)].vertex[0])];
  mesh.tet_part.resize(static_cast<std::size_t>(mesh.num_tets()));
  for (int e = 0; e < mesh.num_tets(); ++e) {
    std::array<int, kNumParts> votes{};
    for (int c = 0; c < 4; ++c)
      ++votes[static_cast<std::size_t>(mesh.node_part[static_cast<std::size_t>(mesh.tets(e, c))])];
    mesh.tet_part[static_cast<std::size_t>(e)] =
        static_cast<Part>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  }
  const QualityReport quality = quality_report(mesh.nodes, mesh.tets);
  require(quality.valid(), "layer '{}' (layered): {} inverted and {} degenerate tets in the template", mesh.region,
          quality.inverted, quality.degenerate);
}

/// A tet mesh of the layer surface by cgal or gmsh and the surface it was meshed from.
struct SizedTetMesh {
  TetMesh tets;
  LayerSurface layer;
  double edge_length = 0.0;  ///< the target edge it was meshed with [m]
};

/// Meshes the layer with the target edge from the layer volume and the preset's tet count. The regular-tet estimate
/// assumes the tets fill the volume freely; a thin layer needs more tets (the thickness must be resolved), so the
/// count is corrected by remeshing with a rescaled edge (exponent between surface-bound 1/2 and volume-bound 1/3
/// scaling) until within ×1.4 of the target.
SizedTetMesh mesh_to_target_size(const LayerMesh& mesh, const LayerGeometry& geometry,
                                 const LayerMeshOptions& options) {
  const Region& region = mesh.region_surface;
  const double volume = enclosed_volume(build_layer_surface(region, geometry, 1.0, 1).surface);
  require(volume > 0.0, "layer '{}': enclosed volume {:.3e} m³ is not positive (inverted layer boundary)", mesh.region,
          volume);
  SizeControl size = size_for_target_tets(volume, target_tets(options.size), options.mesher, options.threads);
  const long target = target_tets(options.size);
  SizedTetMesh out;
  double previous_ratio = 0.0;
  for (int pass = 0;; ++pass) {
    out.layer = build_layer_surface(region, geometry, size.edge_length);
    if (pass == 0) check_layer_boundary(mesh, out.layer);
    out.tets = tetrahedralize(out.layer.surface, options.mesher, size);
    const double ratio = static_cast<double>(out.tets.tets.rows()) / static_cast<double>(target);
    logger()->info("layer '{}' ({}, {}): edge {:.4f} m, {} side layers → {} tets ({:.2f} × target)", mesh.region,
                   mesher_name(options.mesher), size_preset_name(options.size), size.edge_length, out.layer.side_layers,
                   out.tets.tets.rows(), ratio);
    // Stop when close enough, after two corrections, or when the count no longer follows the edge
    // (gmsh keeps every skin vertex, which bounds its count from below).
    if (pass == 2 || (ratio > 1.0 / 1.4 && ratio < 1.4) || std::abs(ratio / previous_ratio - 1.0) < 0.1) break;
    previous_ratio = ratio;
    SizeControl next = size;
    next.edge_length *= std::pow(ratio, 1.0 / 2.5);
    next.surface_distance *= next.edge_length / size.edge_length;
    size = next;
  }
  out.edge_length = size.edge_length;
  logger()->info("layer '{}': {} skin vertices, {} boundary loops, volume {:.4f} m³", mesh.region,
                 region.num_vertices(), region.boundary_loops.size(), volume);
  return out;
}

/// Node kinds and anchors: gmsh nodes that are input vertices take their anchors directly; other boundary nodes are
/// located on the layer surface. Boundary nodes are then snapped onto the anchor's position so that retargeting
/// reproduces the template exactly.
void anchor_boundary_nodes(LayerMesh& mesh, const SizedTetMesh& sized, const LayerGeometry& geometry) {
  const int n = mesh.num_nodes();
  const BoundaryLocation location = locate_boundary_nodes(sized.tets, sized.layer.surface);
  mesh.kind.assign(static_cast<std::size_t>(n), NodeKind::interior);
  mesh.anchor.assign(static_cast<std::size_t>(n), SurfaceAnchor{});
  constexpr double kRimTolerance = 1e-6;  // depth closer than this to 0 or 1 is on the rim
  double largest_snap = 0.0;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    SurfaceAnchor anchor;
    if (!sized.tets.input_vertex.empty() && sized.tets.input_vertex[k] >= 0) {
      anchor = sized.layer.anchors[static_cast<std::size_t>(sized.tets.input_vertex[k])];
    } else if (location.triangle[k] >= 0) {
      anchor = blend_anchor(sized.layer, location.triangle[k], location.bary[k]);
    } else {
      continue;
    }
    if (anchor.depth < kRimTolerance) anchor.depth = 0.0;
    if (anchor.depth > 1.0 - kRimTolerance) anchor.depth = 1.0;
    mesh.kind[k] = anchor.depth == 0.0 ? NodeKind::outer : anchor.depth == 1.0 ? NodeKind::inner : NodeKind::side;
    mesh.anchor[k] = anchor;
    const Eigen::Vector3d snapped = geometry.position(anchor);
    largest_snap = std::max(largest_snap, (snapped - mesh.nodes.row(i).transpose()).norm());
    mesh.nodes.row(i) = snapped.transpose();
  }
  logger()->debug("layer: boundary nodes snapped onto their anchors by at most {:.2e} m", largest_snap);
  const QualityReport snapped_quality = quality_report(mesh.nodes, mesh.tets);
  require(snapped_quality.valid(),
          "layer '{}' ({}): {} inverted and {} degenerate tets after placing boundary nodes on the layer surface",
          mesh.region, mesher_name(mesh.mesher), snapped_quality.inverted, snapped_quality.degenerate);
}

/// Parts: boundary nodes from their anchor's main vertex, interior nodes by harmonic interpolation of the part
/// indicators; tets by the largest summed indicator of their nodes.
void assign_parts(LayerMesh& mesh) {
  const int n = mesh.num_nodes();
  std::vector<char> fixed(static_cast<std::size_t>(n), 0);
  Eigen::MatrixXd indicator = Eigen::MatrixXd::Zero(n, kNumParts);
  for (int i = 0; i < n; ++i) {
    const auto& anchor = mesh.anchor[static_cast<std::size_t>(i)];
    if (!anchor.valid()) continue;
    fixed[static_cast<std::size_t>(i)] = 1;
    for (int s = 0; s < 3; ++s)
      indicator(i, static_cast<int>(mesh.region_surface.part[static_cast<std::size_t>(anchor.vertex[s])])) +=
          anchor.weight(s);
  }
  indicator = HarmonicInterpolator(mesh.nodes, mesh.tets, fixed).extend(indicator);
  mesh.node_part.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    Eigen::Index best = 0;
    indicator.row(i).maxCoeff(&best);
    mesh.node_part[static_cast<std::size_t>(i)] = static_cast<Part>(best);
  }
  mesh.tet_part.resize(static_cast<std::size_t>(mesh.tets.rows()));
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(kNumParts);
    for (int c = 0; c < 4; ++c) sum += indicator.row(mesh.tets(e, c));
    Eigen::Index best = 0;
    sum.maxCoeff(&best);
    mesh.tet_part[static_cast<std::size_t>(e)] = static_cast<Part>(best);
  }
}

/// Skin embedding: nodes where the mesher kept the skin vertices, point location otherwise.
void embed_skin(LayerMesh& mesh, const TetMesh& tet_mesh, const LayerGeometry& geometry) {
  const int n = mesh.num_nodes();
  const int count = mesh.region_surface.num_vertices();
  mesh.skin.node.assign(static_cast<std::size_t>(count), -1);
  if (!tet_mesh.input_vertex.empty())
    for (int i = 0; i < n; ++i) {
      const int input = tet_mesh.input_vertex[static_cast<std::size_t>(i)];
      if (input >= 0 && input < count) mesh.skin.node[static_cast<std::size_t>(input)] = i;
    }
  const detail::PointLocation skin_location = detail::locate_points(mesh.nodes, mesh.tets, geometry.skin);
  mesh.skin.tet = skin_location.tet;
  mesh.skin.bary = skin_location.bary;
  std::vector<std::pair<int, int>> incident(static_cast<std::size_t>(n), {-1, -1});  // node → (tet, corner)
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (int c = 0; c < 4; ++c) incident[static_cast<std::size_t>(mesh.tets(e, c))] = {static_cast<int>(e), c};
  for (int v = 0; v < count; ++v) {
    const auto k = static_cast<std::size_t>(v);
    const int node = mesh.skin.node[k];
    if (node < 0) continue;
    const auto [tet, corner] = incident[static_cast<std::size_t>(node)];
    mesh.skin.tet[k] = tet;
    mesh.skin.bary[k] = Eigen::Vector4d::Unit(corner);
  }
}

}  // namespace

LayerMesh build_layer_mesh(const body::BodyModel& model, const LayerMeshOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  LayerMesh mesh;
  mesh.body_name = model.name;
  const auto names = options.region_names.empty() ? default_region_names() : options.region_names;
  mesh.region = region_key(names);
  mesh.mesher = options.mesher;
  mesh.size = options.size;
  mesh.template_thickness = options.template_thickness;
  require(options.template_thickness > 0.0 && options.template_thickness < 1.0,
          "template thickness h = {}; expected 0 < h < 1", options.template_thickness);
  mesh.region_surface = select_region(model, names);
  mesh.correspondence = skeleton_correspondence(model, mesh.region_surface);
  const LayerGeometry geometry = layer_geometry(model, mesh.region_surface, mesh.correspondence, body::Betas::Zero(),
                                                mesh.template_thickness_field());

  if (options.mesher == Mesher::layered) {
    build_layered_layer(mesh, geometry, options);
    mesh.meshing_seconds = seconds_since(start);
    logger()->info("layer '{}' (layered, {}, {} prism layers): {} nodes, {} tets in {:.1f} s", mesh.region,
                   size_preset_name(options.size), layered_prism_layers(options), mesh.num_nodes(), mesh.num_tets(),
                   mesh.meshing_seconds);
    return mesh;
  }
  const SizedTetMesh sized = mesh_to_target_size(mesh, geometry, options);
  mesh.edge_length = sized.edge_length;
  mesh.nodes = sized.tets.nodes;
  mesh.tets = sized.tets.tets;
  anchor_boundary_nodes(mesh, sized, geometry);
  assign_parts(mesh);
  embed_skin(mesh, sized.tets, geometry);
  mesh.meshing_seconds = seconds_since(start);
  logger()->info("layer '{}' ({}, {}): {} nodes, {} tets in {:.1f} s", mesh.region, mesher_name(options.mesher),
                 size_preset_name(options.size), mesh.num_nodes(), mesh.tets.rows(), mesh.meshing_seconds);
  return mesh;
}

}  // namespace sflsh::meshing
