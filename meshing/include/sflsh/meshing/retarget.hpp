#pragma once
// Retargeting the one common layer discretization to a shape β and thickness field h (docs/architecture.md §3):
// boundary nodes follow their anchors on the shaped skin and the new inner surface; interior nodes
// follow by Laplacian interpolation (one factorization per mesh) in layer coordinates: the skin point
// S and the column vector C = h (c − s) of the boundary anchors are interpolated harmonically, and
// with the harmonic depth δ a node sits at x = S + δ C + r, r being its fixed template residual.
// A change of thickness then moves every node along its column in proportion to its depth, which
// keeps thin (h = 0.1) and thick (h = 0.9) layers valid where interpolating Cartesian displacements
// folds tets near the inner surface.
#include <sflsh/meshing/harmonic.hpp>
#include <sflsh/meshing/layer_mesh.hpp>

namespace sflsh::meshing {

struct RetargetedLayer {
  RowMatrixX3d nodes;      ///< node positions for (β, h), unposed
  LayerGeometry geometry;  ///< shaped skin, skeleton correspondence and h per region vertex
  QualityReport quality;
  int untangled_nodes = 0;  ///< interior nodes moved by the local untangling pass (0 when none was needed)
  double seconds = 0.0;
};

/// What retarget() needs of a shape β alone (Retargeter::shape): the shaped skin s and skeleton points c per
/// region vertex and the harmonic extension E[S] of the anchors' skin points. A fit retargets one subject
/// hundreds of times with different h; with this made once per subject a retarget extends only C = h (c − s).
struct ShapedLayer {
  body::Betas beta;
  RowMatrixX3d skin;               ///< s (R × 3)
  RowMatrixX3d skeleton;           ///< c (R × 3)
  Eigen::MatrixXd skin_extension;  ///< E[S] at every node (N × 3)
};

/// How a retarget checks its result.
enum class RetargetCheck {
  report,  ///< the full QualityReport (dihedral angles, radius–edge ratios, thickness statistics)
  /// one pass with the criteria of QualityReport::valid() only (signed volume, degeneracy); the full report is
  /// made only when that pass fails, for the error message. RetargetedLayer::quality then holds the tet and node
  /// counts alone.
  light,
};

class Retargeter {
 public:
  /// Factorizes the mesh's Laplacian once. The body model must be the one the mesh was built from.
  Retargeter(const body::BodyModel& model, const LayerMesh& mesh, double stiffening = 1.0);

  /// The layer for shape β and thickness field h (one value per region vertex, each in (0, 1)). Throws
  /// naming the body parts, the count and the worst place when tets would invert; never returns a
  /// mesh with inverted tets.
  RetargetedLayer retarget(const body::Betas& beta, const Eigen::VectorXd& thickness) const;
  RetargetedLayer retarget(const body::Betas& beta, double uniform_thickness) const;
  /// The same for a shape prepared by shape(): bit-identical nodes to retarget(shaped.beta, thickness).
  RetargetedLayer retarget(const ShapedLayer& shaped, const Eigen::VectorXd& thickness,
                           RetargetCheck check = RetargetCheck::report) const;
  /// The part of a retarget that depends on β alone (once per subject).
  ShapedLayer shape(const body::Betas& beta) const;
  /// (dx/dh) dh: how the retargeted nodes move (N × 3) per change dh of the thickness field (R values). Exact: for
  /// a shape the nodes are affine in h (x = E[S] + δ ⊙ E[C] + r with C = h (c − s) at the anchors; boundary
  /// nodes at Σ_k w_k (s_k + depth h_k (c_k − s_k))), so this is their linear part, independent of h. It
  /// holds wherever retarget() needed no untangling (RetargetedLayer::untangled_nodes == 0).
  RowMatrixX3d node_derivative(const ShapedLayer& shaped, const Eigen::VectorXd& dthickness) const;

  /// A field given per region vertex (R×k) carried to every node (N×k): at boundary nodes through
  /// their anchors (depth does not change the value), inside by the same Laplacian interpolation.
  Eigen::MatrixXd extend_surface_field(const Eigen::MatrixXd& per_region_vertex) const;

  /// The depth coordinate at every node (docs/physics.md §1.3): 0 on the skin, 1 on the inner surface, the
  /// anchor's depth on the side walls, harmonic inside. Its gradient gives the through-thickness normal.
  Eigen::VectorXd depth_field() const;
  /// depth_field() as computed once at construction.
  const Eigen::VectorXd& depth() const { return depth_; }

  const LayerMesh& mesh() const { return mesh_; }
  const HarmonicInterpolator& interpolator() const { return interpolator_; }

 private:
  /// Per boundary node: skin point S and column vector C of its anchor for a geometry (N×6, zero rows
  /// for interior nodes).
  Eigen::MatrixXd layer_coordinates(const LayerGeometry& geometry) const;
  /// The column vectors C alone (N × 3).
  Eigen::MatrixXd column_coordinates(const LayerGeometry& geometry) const;

  const body::BodyModel& model_;
  const LayerMesh& mesh_;
  HarmonicInterpolator interpolator_;
  Eigen::VectorXd depth_;                  ///< harmonic depth δ per node
  Eigen::MatrixXd residual_;               ///< template x − (S + δ C) per node (zero on the boundary)
  std::vector<std::vector<int>> tets_of_;  ///< tets around each node
};

}  // namespace sflsh::meshing
