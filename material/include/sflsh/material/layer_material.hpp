#pragma once
// The heterogeneous material of a layer mesh: control points on the layer's skin region, their
// biharmonic basis, and κ = (h, Y_t, Y_n) carried from the control points to every skin vertex, node
// and tet (docs/architecture.md §4), with the through-thickness normal per tet.
#include <sflsh/material/biharmonic_basis.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/material/parameters.hpp>
#include <sflsh/meshing/retarget.hpp>

namespace sflsh::material {

/// Sampling density of control points per part: denser on the torso (paper Fig. 2).
inline constexpr double kTorsoDensity = 1.5;

/// For each region vertex, its left/right mirror (x → −x) among the region's vertices, or −1 when no
/// vertex lies within `tolerance` [m] of the mirrored position (SMPL-like bodies are symmetric).
std::vector<int> region_mirror_map(const meshing::LayerMesh& mesh, const body::BodyModel& model,
                                   double tolerance = 2e-3);

/// The template positions of the layer's region vertices (R × 3), the surface κ and φ live on.
meshing::RowMatrixX3d region_positions(const body::BodyModel& model, const meshing::LayerMesh& mesh);

/// `count` control points on the layer's region (nested in count, symmetric pairs, denser on the
/// torso), as BODY vertex indices.
std::vector<int> layer_control_points(const body::BodyModel& model, const meshing::LayerMesh& mesh, int count);

/// The biharmonic basis over the region's vertices (R × N) for control points given as body vertex
/// indices. Throws naming a control vertex that is not in the layer's region.
BiharmonicBasis layer_basis(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                            const std::vector<int>& control_body_vertices);

/// Provisional defaults until the full-space calibration (docs/physics.md §6): h = 0.5, Y_t = 5 kPa,
/// Y_n = 2 kPa at every control point.
Kappa default_kappa();

/// A material file with `count` control points at default_kappa() for a subject.
MaterialFile default_material(const body::BodyModel& model, const meshing::LayerMesh& mesh, int count,
                              const std::string& subject);

struct LayerMaterialFields {
  KappaMatrix vertex;            ///< per region vertex (R × 3)
  KappaMatrix node;              ///< per mesh node (harmonic extension of the skin values)
  KappaMatrix tet;               ///< per tet: mean of its nodes
  meshing::RowMatrixX3d normal;  ///< per tet: through-thickness unit normal (towards the skin)
};

/// κ from control values (N × 3, physical) through φ (R × N) to vertices, nodes and tets of the layer
/// whose node positions are `nodes` (retargeted with the thickness field `fields.vertex.col(0)`).
LayerMaterialFields layer_material_fields(const meshing::Retargeter& retargeter, const Eigen::MatrixXd& phi,
                                          const KappaMatrix& kappa_control, const meshing::RowMatrixX3d& nodes);
/// The same from κ given at every region vertex (R × 3), e.g. a field not spanned by any control points.
LayerMaterialFields layer_material_fields(const meshing::Retargeter& retargeter, const KappaMatrix& kappa_vertex,
                                          const meshing::RowMatrixX3d& nodes);

}  // namespace sflsh::material
