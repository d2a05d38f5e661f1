#pragma once
// The reduced model of a subject's layer (SFLSH §3, paper Fig. 2 middle): the 24 skeleton bones as bone
// handles (the attached inner and side nodes, grouped by their dominant joint) and P point handles inside
// the layer (mesh nodes at mid-depth under the material control-point sites: deterministic, nested in P,
// left/right symmetric, denser on the torso), linearly precise biharmonic weights, the reduced basis, and
// the data-oblivious cubature. Handles, weights and cubature are one common discretization built on the
// template layer (β = 0) and cached beside the template mesh; handle positions follow retargeting because
// handles are mesh nodes.
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/subspace.hpp>
#include <sflsh/reduced/weights.hpp>

#include <filesystem>
#include <string>

namespace sflsh::reduced {

struct ReducedModelOptions {
  int point_handles = 86;
  /// K cubature tets; 0 = exact (every tet); −1 = auto, max(200, ⌈0.8 · coordinates⌉). Measured on the
  /// coarse layer (sflsh compare): with K below ≈ 0.75 · coordinates the subspace finds deformations the
  /// cubature does not see — stable on the sampled tets while unsampled ones leave the material's range.
  int cubature = -1;
  /// Auto cubature (cubature = −1) starts at max(200, ⌈0.8 · coordinates⌉) tets and grows by 25 % until every
  /// direction of the subspace is at most this many times stiffer in the exact rest stiffness than in the cubature's
  /// (cubature.hpp, cubature_coverage); explicit counts are only measured against it.
  double coverage_ratio = 4.0;
  bool cubature_auto = false;  ///< set by build_reduced_model (part of the cache key)
  CubatureWeighting weighting = CubatureWeighting::nnls;
  BasisOptions basis;
  std::filesystem::path cache_dir;  ///< empty: meshing::default_cache_dir()
  bool use_cache = true;
};

struct BodyHandles {
  std::vector<int> point_nodes;     ///< P mesh nodes
  std::vector<int> point_vertices;  ///< the body vertex each point handle sits under
  std::vector<int> bone_of_node;    ///< per node: joint of an attached node, −1 for free nodes
  /// Point handles first (one node each), then one set per joint that has attached nodes.
  HandleSets sets() const;
  std::vector<int> bone_joints() const;  ///< the joints of the bone sets, in order
};

/// Places the handles on a body layer (template mesh, its depth field and node skinning weights).
BodyHandles place_body_handles(const model::BodyLayer& layer, int point_handles);

struct ReducedModel {
  BodyHandles handles;
  Subspace subspace;
  Cubature cubature;
  std::string cache_key;
  std::string cache_outcome;  ///< "hit" | "built" | "off"
  double build_seconds = 0.0;
};

/// The reduced model of `layer`. Throws naming the cause (too many handles for the mesh, a failed solve, an
/// unreadable cache entry — which is then rebuilt, with a warning).
ReducedModel build_reduced_model(const model::BodyLayer& layer, const ReducedModelOptions& options);

/// The largest point-handle count a layer takes (a quarter of its skin vertices).
int max_point_handles(const model::BodyLayer& layer);

/// The cubature count that `options` asks for (resolves −1 = auto).
int resolved_cubature_count(const ReducedModelOptions& options);

/// The template problem the cubature is fitted on: template nodes and tets, isotropic default tissue.
model::Problem template_problem(const model::BodyLayer& layer);

/// The model's cubature fitted again with the tets `excluded` left out (ascending; those a local patch integrates
/// exactly, local_basis.hpp): points and weights for the energy of the other tets alone, chosen as
/// build_reduced_model chooses them for `requested` (exact, a count, or auto with its coverage). Tet indices are the
/// layer's; no excluded tet is a point.
Cubature cubature_outside(const model::BodyLayer& layer, const Subspace& subspace, const ReducedModelOptions& requested,
                          const std::vector<int>& excluded);

}  // namespace sflsh::reduced
