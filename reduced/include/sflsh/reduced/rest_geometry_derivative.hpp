#pragma once
// How the reduced backward-Euler step gradient G(q) = ∇Φ(q) depends on the rest geometry X (beyond SFLSH §5,
// which differentiates σ in the thickness h by one-sided finite differences). The thickness moves the rest nodes,
// exactly linearly: dX_j = (dX/dh) φ_j (meshing::Retargeter::node_derivative), so the forward sensitivities
// (reduced_sensitivity.hpp) take thickness columns once ∂G/∂h_j at fixed q and history is known. What depends on X,
// and is differentiated here in closed form:
//   - per cubature tet: D_m, hence D_m⁻¹ (dD_m⁻¹ = −D_m⁻¹ dD_m D_m⁻¹), V (dV = V tr(D_m⁻¹ dD_m)), the vectors
//     c_s = Σ_a B_as g_a of F = F_D + Σ_s t_s c_sᵀ (cubature_elastic.hpp), and the material axis
//     n = −∇δ/|∇δ| (dn = −(I − nnᵀ) d∇δ / |∇δ|, d∇δ = −D_m⁻ᵀ dD_mᵀ ∇δ; δ the fixed harmonic depth); with fixed
//     attachments x_D = X, so F_D = D_s D_m⁻¹ = I whatever X;
//   - the lumped masses m_i = ρ Σ_{e ∋ i} V_e / 4 of the nodes the basis moves;
//   - the skinned positions z_i = A_i(t) X_i + d_i(t) of the rest shape in the motion, and through them the
//     prediction p̃ = p_n + h w_n (w_n = (p_n − p_{n−1})/h_prev, w_0 = Ȧ(t₀) X + ḋ(t₀), the kinematic velocity).
// Then, with p = z + A B q at t_{n+1},
//   ∂G/∂h_j = Σ_c [dω_c P_c c_s + ω_c (∂P/∂F : dF_c + ∂P/∂n dn_c) c_s + ω_c P_c dc_s]           (elastic)
//           + Σ_i b_i ⊗ A_iᵀ [m_i (dz_i − dp̃_i) + dm_i (p_i − p̃_i)] / h² − Σ_i b_i ⊗ dm_i A_iᵀ g   (inertia, gravity).
// ∂P/∂n is the one derivative not in closed form: a central difference of the closed-form stress over a rotation of
// the axis by 1e-5 rad (error ~1e-10 relative), as a 9 × 3 matrix per point and substep, so its cost does not grow
// with the number of columns. Held fixed, with the reason: the subspace B and the cubature weights (built once on
// the template, shared by every subject and h: the model does not change with h), the skin embedding and the
// normals of the σ split (the skin does not move with h), the Young moduli per tet (a harmonic extension of the
// surface field that does not depend on X), and the axis of a tet whose four nodes share one depth (it borrows its
// neighbours' mean: none on the layered meshes' cubature). Lumped mass, backward Euler and fixed attachments only.
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::reduced {

class RestGeometryDerivative {
 public:
  /// @param[in] directions  dX_j per column (N × 3 each) [m per unit of the column's parameter]
  /// @param[in] depth       the retargeter's harmonic depth per node (meshing::Retargeter::depth)
  /// @param[in] inertia_on  whether the step has inertia (false: quasi-static, gravity alone)
  /// The problem, subspace, elastic term, inertia and directions must outlive this object.
  RestGeometryDerivative(const model::Problem& problem, const Subspace& subspace, const CubatureElastic& elastic,
                         const ReducedInertia& inertia, const std::vector<meshing::RowMatrixX3d>& directions,
                         const Eigen::VectorXd& depth, bool inertia_on);

  int columns() const { return columns_; }
  /// The posed history at the initial time t₀: positions p₀ and velocities w₀ of the inertia nodes (3 per node).
  void initialize(double t0, const Eigen::VectorXd& p0, const Eigen::VectorXd& w0);
  /// ∂G/∂X · dX_j for every column (3S × columns) at the converged q of the substep of size dt that ends at the
  /// inertia's current time (ReducedInertia::set_time done for it).
  Eigen::MatrixXd gradient_derivative(const Eigen::VectorXd& q, double dt) const;
  /// Moves the history on by the converged substep (after gradient_derivative).
  void advance(const Eigen::VectorXd& q, double dt);
  /// Takes in the cubature points the elastic term gained since (the guard's, reduced_solver_guard.cpp).
  void add_points();

 private:
  /// A_i(t) dX_j at the inertia nodes, for the frame the inertia holds now (3 per node × columns).
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMatrix posed_directions() const;
  /// dD_m of tet e along direction j (its edge vectors' derivatives, columns 1..3 minus 0).
  Eigen::Matrix3d rest_shape_derivative(int e, int j) const;

  const model::Problem& problem_;
  const Subspace& subspace_;
  const CubatureElastic& elastic_;
  const ReducedInertia& inertia_;
  const std::vector<meshing::RowMatrixX3d>& directions_;
  Eigen::VectorXd depth_;  ///< the harmonic depth per node
  int columns_ = 0;
  bool inertia_on_ = true;
  // Row-major: the loops read one node's 3 × columns block at a time.
  RowMatrix node_directions_;  ///< dX_j at the inertia nodes (3 per node × columns)
  RowMatrix mass_derivative_;  ///< dm_i per active node × columns [kg]
  // Per cubature point p, one column per direction j: dV/V (row p), dc_s of its functions (parallel to
  // elastic.point_functions(p); rows 3 (point_offset_[p] + s) + axis) and dn (rows 3p + axis).
  RowMatrix volume_rate_;
  std::vector<int> point_offset_;
  RowMatrix dc_;
  RowMatrix dn_;
  // The posed history of the rest geometry: p, w (3 per inertia node) and their explicit derivatives.
  Eigen::VectorXd p_, w_;
  RowMatrix dp_, dw_;
};

}  // namespace sflsh::reduced
