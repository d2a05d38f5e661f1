#pragma once
// The soft-tissue layer as a tet mesh: one common discretization of the template, built once per body
// model, region, size and backend, then retargeted to any shape β and thickness field h.
#include <sflsh/meshing/correspondence.hpp>
#include <sflsh/meshing/quality.hpp>
#include <sflsh/meshing/tet_backend.hpp>

#include <string>
#include <vector>

namespace sflsh::meshing {

/// Size presets: the target tet count of the template layer.
enum class SizePreset { coarse, medium, fine };
SizePreset parse_size_preset(const std::string& name);  ///< "coarse" | "default" | "fine"
const char* size_preset_name(SizePreset preset);        ///< "coarse" | "default" | "fine"
long target_tets(SizePreset preset);                    ///< 10 k, 50 k, 200 k

/// How the region's skin vertices are found in the mesh. gmsh keeps them as mesh nodes (node ≥ 0);
/// CGAL resamples the boundary, so they are embedded: x = Σ bary_k nodes[tet_k] (bary may leave
/// [0, 1] by the surface approximation error, which keeps the embedding exact in the template).
struct SkinEmbedding {
  std::vector<int> node;              ///< per region vertex: the mesh node, or −1
  std::vector<int> tet;               ///< per region vertex: the containing (or nearest) tet
  std::vector<Eigen::Vector4d> bary;  ///< per region vertex: coordinates in that tet
};

struct LayerMesh {
  // Key (what the mesh was built from); see layer_cache.hpp.
  std::string body_name;
  std::string region;  ///< region_key(names)
  Mesher mesher = Mesher::cgal;
  SizePreset size = SizePreset::medium;
  double template_thickness = 0.5;  ///< uniform h of the template
  double edge_length = 0.0;         ///< target edge given to the mesher [m]

  Region region_surface;  ///< the region on the body skin
  SkeletonCorrespondence correspondence;
  RowMatrixX3d nodes;                 ///< template positions (β = 0, h = template_thickness)
  RowMatrixX4i tets;                  ///< positively oriented
  std::vector<NodeKind> kind;         ///< per node
  std::vector<SurfaceAnchor> anchor;  ///< per node; invalid for interior nodes
  std::vector<Part> node_part;        ///< per node
  std::vector<Part> tet_part;         ///< per tet
  SkinEmbedding skin;
  double meshing_seconds = 0.0;

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
  int num_tets() const { return static_cast<int>(tets.rows()); }
  /// Indices of nodes of a kind, ascending.
  std::vector<int> nodes_of_kind(NodeKind kind) const;
  /// The skin nodes on the region's boundary curves (outer nodes whose anchor lies on a boundary loop:
  /// where the side wall meets the skin), ascending. They close the layer like the side wall.
  std::vector<int> rim_nodes() const;
  /// The template thickness as a field over the region's vertices.
  Eigen::VectorXd template_thickness_field() const;
  /// Skin positions (R×3) read from node positions through the embedding.
  RowMatrixX3d skin_positions(const RowMatrixX3d& node_positions) const;
};

struct LayerMeshOptions {
  std::vector<std::string> region_names;  ///< empty: default_region_names()
  Mesher mesher = Mesher::cgal;
  SizePreset size = SizePreset::medium;
  double template_thickness = 0.5;
  int threads = 2;
  /// layered mesher only: prism layers through the thickness; 0: the size preset's (1, 2, 8 for coarse, default,
  /// fine). More layers keep thick layers valid where the columns converge (docs/meshing.md, "Every mesher at every
  /// thickness").
  int layers = 0;
};

/// The prism layers the layered mesher builds with `options` (its `layers`, else the size preset's).
int layered_prism_layers(const LayerMeshOptions& options);

/// Meshes the template layer (β = 0, uniform h = template_thickness). Throws when the layer boundary
/// self-intersects or the mesher returns inverted or degenerate tets.
LayerMesh build_layer_mesh(const body::BodyModel& model, const LayerMeshOptions& options);

/// The quality report of a mesh with node positions `nodes`, with the layer thickness stats of `geometry`.
QualityReport layer_quality(const LayerMesh& mesh, const RowMatrixX3d& nodes, const LayerGeometry& geometry);

}  // namespace sflsh::meshing
