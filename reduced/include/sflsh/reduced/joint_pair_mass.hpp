#pragma once
// The reduced mass of skinned node maps by joint pairs (reduced_inertia.hpp). With A_i(t) = Σ_k w_ik R_k(t)
// (the linear parts of the blended joint transforms) and the node-level mass M (lumped: diagonal m_i;
// consistent: M_ij of mass.hpp) over the active nodes,
//   Σ_ij M_ij b_is b_jr A_i(t)ᵀ A_j(t') = Σ_kl T_kl(s, r) R_k(t)ᵀ R_l(t'),   T_kl(s, r) = Σ_ij M_ij w_ik w_jl b_is
//   b_jr,
// precomputed once, so an evaluation costs one 3×3 product per joint pair and entry of T, not a pass over
// the nodes. Symmetries: always T_kl(s, r) = T_lk(r, s) (M is symmetric); lumped, T is moreover symmetric in
// (k, l) and in (s, r) separately. Hence both are stored for k ≤ l and s ≤ r: lumped as a = T_kl(s, r) alone,
// consistent as the pair a = T_kl(s, r), b = T_lk(s, r) (= T_kl(r, s)).
#include <sflsh/model/skinned_trajectory.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

namespace sflsh::reduced {

class JointPairMass {
 public:
  /// Lumped: `mass` per active node (active[a] is the mesh node of entry a).
  static JointPairMass lumped(const model::SkinnedTrajectory& skinned, const Subspace& subspace,
                              const std::vector<int>& active, const std::vector<double>& mass);
  /// Consistent: `mass` is M restricted to the active nodes (active × active, entry (a, b) = M_{active[a] active[b]}).
  static JointPairMass consistent(const model::SkinnedTrajectory& skinned, const Subspace& subspace,
                                  const std::vector<int>& active,
                                  const Eigen::SparseMatrix<double, Eigen::RowMajor>& mass);

  /// M += scale · Σ_kl T_kl ⊗ R_k(at)ᵀ R_l(other) (3S × 3S; symmetric when at = other).
  void add(const model::JointTransforms& at, const model::JointTransforms& other, double scale,
           Eigen::MatrixXd& M) const;
  /// Stored entries over all joint pairs (for reporting).
  std::size_t num_entries() const;

 private:
  struct PairTerm {
    int k = 0, l = 0;
    std::vector<int> s, r;
    std::vector<double> value;          ///< T_kl(s, r)
    std::vector<double> value_swapped;  ///< T_lk(s, r) (consistent, k < l); empty otherwise
  };
  std::vector<PairTerm> pairs_;
};

}  // namespace sflsh::reduced
