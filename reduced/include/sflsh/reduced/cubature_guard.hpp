#pragma once
// The guard of the tets outside the cubature (docs/reduced.md, "Robust cubature"). The cubature energy sees only
// its points, so a subspace state can strain a tet outside the set far beyond the material's range while the
// reduced energy stays low. The guard watches every tet that carries no cubature weight, cheaply. At a reference
// state q_ref every guarded tet gets the radius r_e in F within which its Fung exponent x = 2Ψ₀/c stays below the
// limit (Ψ₀ ≤ (μ₀ + 3/2 λ₀⁺)‖Ê‖², ‖Ê − Ê_ref‖ ≤ ‖P_Y‖² ‖E − E_ref‖, ‖E − E_ref‖ ≤ ‖F_ref‖₂ r + r²/2). With
// F = F_D + Σ_s t_s c_sᵀ (cubature_elastic.hpp), the fixed skeleton counted as one more function g with Δt_g = 0 and
// c_g = −Σ_s c_s, any anchor a among the tet's functions and g gives exactly
//   F_e(q) − F_e(q_ref) = Σ_{s ∈ S_e ∪ {g}, s ≠ a} (Δt_s − Δt_a) c_sᵀ,  so  ‖ΔF_e‖_F ≤ Σ_{s ≠ a} ‖Δt_s − Δt_a‖ ‖c_s‖,
// with a the entry of largest ‖c‖. Where the basis sums to one (inside the flesh) c_g vanishes and a region that
// moves as a whole strains nothing: the bound sees differences between neighbouring functions, not their motion.
// The tets sharing an anchor form a cluster with its own reference q_ref (the differences d_s = t_s − t_a of its
// pairs at its last renewal), so that a region in motion renews its own tets and leaves the rest alone. A check
// compares each pair's ‖d_s − d_s,ref‖ with its budget β = min over the cluster's tets using it of r_e / L_e,
// L_e = Σ_{s ≠ a} ‖c_s‖ (O(pairs)); only the tets using a pair beyond its budget get their own bound, and those whose
// bound exceeds r_e are evaluated exactly. When more than 30 % of a cluster's tets need it, the cluster's reference
// moves to q (its tets evaluated, radii renewed).
// The limit of a tet is the smaller of two: the exponent limit, and the exponent at which its Fung energy
// (c/2)(eˣ − 1) V reaches the energy limit, x_E = ln(1 + 2 E_max / (c V)) — an unseen tet may hold at most E_max.
// Tets over their limit are returned: the solver adds them to the cubature and solves the substep again
// (reduced_solver.hpp).
#include <sflsh/model/problem.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <span>
#include <vector>

namespace sflsh::reduced {

/// A guarded tet over the limit at a full check.
struct GuardViolation {
  int tet = -1;
  double exponent = 0.0;  ///< its Fung exponent x = 2Ψ₀/c (+∞ for a non-finite F)
};

class CubatureGuard {
 public:
  /// Guards every tet of `problem` that carries no weight in `cubature`; `exponent_limit` is the x above which a
  /// tet counts as leaving the material's range (the energy itself refuses x > material::kFungExponentCap), and
  /// `energy_limit` [J] the Fung energy a guarded tet may hold (+∞: the exponent limit alone).
  CubatureGuard(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                double exponent_limit, double energy_limit = model::kInfinity);

  /// The prescribed state changed (attached nodes driven): the next check is a full one.
  void set_prescribed_state(const Eigen::VectorXd& x_prescribed);
  /// The guarded tets over the limit at q; empty when none is (mostly proved by the bound alone).
  std::vector<GuardViolation> check(const Eigen::VectorXd& q);
  /// Stops guarding `tet` (it joined the cubature).
  void release(int tet);

  int num_guarded() const { return guarded_; }
  /// Checks, checks that renewed every cluster's reference (every tet evaluated), and tets evaluated exactly in all.
  int checks() const { return checks_; }
  int full_checks() const { return full_checks_; }
  long exact_evaluations() const { return exact_; }
  /// Checks that needed the per-tet bound (some function moved beyond its budget β_s).
  int tet_passes() const { return tet_passes_; }
  /// Wall time of the per-tet passes and of the renewals [s] (the O(S) checks are not timed).
  double pass_seconds() const { return pass_seconds_; }
  double renew_seconds() const { return renew_seconds_; }
  double exponent_limit() const { return limit_; }
  double energy_limit() const { return energy_limit_; }
  /// The smallest limit of a guarded tet (the energy limit makes it per tet).
  double smallest_tet_limit() const;
  /// The largest exponent of a guarded tet at its cluster's last renewal.
  double last_max_exponent() const;
  /// Clusters (the tets sharing one anchor, each with its own reference) and renewals of one cluster.
  int num_clusters() const { return static_cast<int>(cluster_offset_.size()) - 1; }
  int cluster_renewals() const { return cluster_renewals_; }

 private:
  /// x of point p at q, and (when `radius`) its radius r in F below the limit.
  double exponent(int point, const Eigen::VectorXd& q, double* radius) const;
  /// Each point's terms, its anchor among its functions and g, and the pairs (edges) they use, cluster by cluster.
  void build_terms(int num_functions);
  /// Moves cluster c's reference to q (t: the coordinates, 3 per function and g): its tets evaluated exactly (those
  /// over their limit appended to `over`), their radii, its pairs' budgets and reference differences.
  void renew_cluster(int cluster, const Eigen::VectorXd& q, const Eigen::VectorXd& t,
                     std::vector<GuardViolation>& over);
  /// Point p's ‖ΔF‖_F from its cluster's reference, summed exactly from its terms (the edges' current moves).
  double change_norm(int point) const;
  /// The tets of cluster c using the pairs beyond their budget (`edges`): bounded, then ‖ΔF‖ computed where the bound
  /// fails; those past r_e evaluated exactly, or the cluster renewed when they are too many.
  void pass_cluster(int cluster, std::span<const int> edges, const Eigen::VectorXd& q, const Eigen::VectorXd& t,
                    std::vector<GuardViolation>& over);

  const model::Problem& problem_;
  CubatureElastic tets_;             ///< the guarded tets as points of weight 1 (their F(q), S_e and c_s)
  std::vector<char> active_;         ///< per point: still guarded
  std::vector<double> spectral_;     ///< ‖P_Y‖₂² per point
  std::vector<double> point_limit_;  ///< x limit per point: min(limit_, x_E)
  std::vector<double> allowed_;      ///< the ‖Ê‖_F at which x reaches its limit, per point (+∞: Fung off)
  std::vector<int> point_of_tet_;    ///< −1 for tets not guarded
  int ground_ = 0;                   ///< the index of the fixed function g (= S)
  // Per point, its terms ‖Δd_s‖ ‖c_s‖ (d_s = t_s − t_a): the pair (edge) of each and ‖c_s‖, in [offset_[p],
  // offset_[p+1]).
  std::vector<int> offset_;
  std::vector<int> term_edge_;
  std::vector<double> term_norm_;
  std::vector<double> scaled_;                ///< ‖c_s‖ / r_e, parallel to the terms (+∞ when r_e = 0)
  std::vector<Eigen::Vector3d> term_vector_;  ///< c_s (c_g for the skeleton's term), parallel to the terms
  std::vector<double> radius_;                ///< r_e per point around its cluster's reference
  // A cluster: the points of one anchor a (a function or g), each with its own reference. Edges are numbered
  // cluster by cluster: cluster a owns edges [cluster_edge_offset_[a], cluster_edge_offset_[a+1]).
  std::vector<int> cluster_offset_, cluster_points_;  ///< the points of each cluster (CSR)
  std::vector<int> cluster_edge_offset_;
  std::vector<int> edge_function_, edge_anchor_;  ///< the pair (s, a) of each edge
  std::vector<int> edge_offset_, edge_points_;    ///< the points using each edge (CSR), by their budget ascending
  std::vector<double> edge_point_budget_;         ///< r_e / L_e of each entry of edge_points_
  std::vector<double> point_budget_;              ///< r_e / L_e per point
  Eigen::VectorXd edge_reference_;                ///< d_s = t_s − t_a at the cluster's reference, 3 per edge
  Eigen::VectorXd edge_moved_;                    ///< d_s − d_s,ref per edge, 3 each (scratch)
  std::vector<double> moved_;                     ///< ‖d_s − d_s,ref‖ per edge (scratch)
  std::vector<double> budget_;                    ///< β per edge
  std::vector<double> cluster_max_;               ///< the largest exponent at the cluster's last renewal
  std::vector<unsigned> visited_;                 ///< per point: the generation of the check that last bounded it
  unsigned generation_ = 0;
  bool valid_ = false;  ///< every cluster has a reference for the current prescribed state and q size
  Eigen::Index q_size_ = 0;
  double limit_ = 0.0;
  double energy_limit_ = model::kInfinity;
  /// Renew a cluster when more of its tets than this fraction need evaluating. 0.05 renewed the clusters of a
  /// bending motion at almost every check (shake_hips, coarse: 2,224 renewals in 300 frames, 3.4 ms per frame);
  /// 0.3: 0.8 ms per frame there, jiggle_on_toes unchanged (docs/results/performance.md).
  double renew_fraction_ = 0.3;
  int guarded_ = 0, full_checks_ = 0, cluster_renewals_ = 0, checks_ = 0, tet_passes_ = 0;
  long exact_ = 0;
  double pass_seconds_ = 0.0, renew_seconds_ = 0.0;
};

}  // namespace sflsh::reduced
