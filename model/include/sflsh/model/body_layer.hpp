#pragma once
// A subject's soft-tissue layer set up for the full-space solver (docs/architecture.md §4, docs/physics.md §5): the
// template layer retargeted to β and the material's thickness field, the heterogeneous κ per tet, lumped masses, inner
// and side nodes attached to the skinned body (Dirichlet: zero elastic displacement), and the skinning trajectory that
// carries the unposed elastic state to posed positions along a motion.
#include <sflsh/body/motion.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/skin_material.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/meshing/retarget.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/model/skinned_trajectory.hpp>

#include <filesystem>
#include <memory>
#include <string>

namespace sflsh::model {

struct BodyLayerOptions {
  meshing::Mesher mesher = meshing::Mesher::layered;
  meshing::SizePreset size = meshing::SizePreset::medium;
  std::filesystem::path cache_dir;   ///< template mesh cache; empty: meshing::default_cache_dir()
  double density = 1000.0;           ///< ρ [kg/m³]
  MassKind mass = MassKind::lumped;  ///< lumped or consistent inertia (mass.hpp)
  bool gravity = false;  ///< g = (0, −9.81, 0) in the world frame (Y up); off by default (docs/physics.md §5)
  double stiffness_scale = 1.0;  ///< multiplies Y_t and Y_n
  material::ExponentOverflow overflow = material::ExponentOverflow::kThrow;
};

/// Everything a body simulation needs. Movable; the body model passed to build_body_layer must outlive it.
struct BodyLayer {
  body::Betas beta;
  /// The layer mesh the nodes were retargeted from: the template (β = 0), or the subject's own where the template
  /// inverted tets (`remeshed`; meshing/subject_layer.hpp). On the heap so that references to it stay valid.
  std::unique_ptr<meshing::LayerMesh> mesh;
  bool remeshed = false;
  std::string fallback;                  ///< when remeshed: the layer that replaced the template
  meshing::RetargetedLayer layer;        ///< nodes for (β, h)
  material::MaterialFile material;       ///< the material used (given, or the defaults)
  material::LayerMaterialFields fields;  ///< κ per region vertex, node, tet; normals per tet
  Eigen::VectorXd depth;                 ///< harmonic depth per node (0 skin, 1 bone)
  RowMatrixX3d shaped;                   ///< the body's shaped template T_S (n×3)
  std::shared_ptr<const MotionCurve> curve;
  std::shared_ptr<const SkinnedTrajectory> trajectory;
  Problem problem;  ///< validated
  const body::BodyModel* model = nullptr;
  RowMatrixX3d rest_skin;                                           ///< the region's skin at the rest state (R×3)
  std::vector<std::vector<std::pair<int, double>>> vertex_weights;  ///< per body vertex: its non-zero skinning weights

  /// Unposed elastic displacement of the region's skin vertices (R×3) at state x (3N).
  RowMatrixX3d surface_displacement(const Eigen::VectorXd& x) const;
  /// The whole posed body surface (n×3) at time t with the region's skin displaced by x: exactly the
  /// `sflsh motion export` positions when x is the rest state and t a frame time.
  RowMatrixX3d posed_surface(const Eigen::VectorXd& x, double t) const;
  /// The whole posed body surface (n×3) at time t with the region's skin displaced by u (R×3, unposed).
  RowMatrixX3d posed_surface_from_displacement(const RowMatrixX3d& u, double t) const;
};

/// Builds the layer of subject β for a motion. `material` null: material::default_material at
/// `control_points` points (checked against the body otherwise). Throws naming the cause.
BodyLayer build_body_layer(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion,
                           const material::MaterialFile* material, int control_points, const BodyLayerOptions& options);

}  // namespace sflsh::model
