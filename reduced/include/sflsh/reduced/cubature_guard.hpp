#pragma once
// The guard of the tets outside the cubature (docs/reduced.md, "Robust cubature"). The cubature energy sees only
// its points, so a subspace state can strain a tet outside the set far beyond the material's range while the
// reduced energy stays low. The guard watches every tet that carries no cubature weight, cheaply. At a reference
// state q_ref every guarded tet gets the radius r_e in F within which its Fung exponent x = 2Ψ₀/c stays below the
// limit (Ψ₀ ≤ (μ₀ + 3/2 λ₀⁺)‖Ê‖², ‖Ê − Ê_ref‖ ≤ ‖P_Y‖² ‖E − E_ref‖, ‖E − E_ref‖ ≤ ‖F_ref‖₂ r + r²/2), and since
//   ‖F_e(q) − F_e(q_ref)‖_F ≤ Σ_{s ∈ S_e} ‖t_s − t_ref,s‖ ‖c_s‖      (F = F_D + Σ_s t_s c_sᵀ, cubature_elastic.hpp)
// a check first compares each ‖t_s − t_ref,s‖ with the budget β_s = min over the tets touching s of r_e / L_e (O(S));
// only the tets touching a function beyond its budget get their own bound, and those whose bound exceeds r_e are
// evaluated exactly. When many need it the reference moves to q (every tet evaluated, radii renewed).
// The limit of a tet is the smaller of two: the exponent limit, and the exponent at which its Fung energy
// (c/2)(eˣ − 1) V reaches the energy limit, x_E = ln(1 + 2 E_max / (c V)) — an unseen tet may hold at most E_max.
// Tets over their limit are returned: the solver adds them to the cubature and solves the substep again
// (reduced_solver.hpp).
#include <sflsh/model/problem.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/subspace.hpp>

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
  /// Checks, checks that renewed the reference (every tet evaluated), and tets evaluated exactly in all.
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
  /// The largest exponent of a guarded tet at the last renewal of the reference.
  double last_max_exponent() const { return last_max_; }

 private:
  /// x of point p at q, and (when `radius`) its radius r in F below the limit.
  double exponent(int point, const Eigen::VectorXd& q, double* radius) const;
  std::vector<GuardViolation> renew(const Eigen::VectorXd& q);

  const model::Problem& problem_;
  CubatureElastic tets_;             ///< the guarded tets as points of weight 1 (their F(q), S_e and c_s)
  std::vector<char> active_;         ///< per point: still guarded
  std::vector<double> spectral_;     ///< ‖P_Y‖₂² per point
  std::vector<double> point_limit_;  ///< x limit per point: min(limit_, x_E)
  std::vector<double> allowed_;      ///< the ‖Ê‖_F at which x reaches its limit, per point (+∞: Fung off)
  std::vector<double> scaled_;       ///< ‖c_s‖ / r_e, parallel to the points' functions (+∞ when r_e = 0)
  std::vector<int> offset_;          ///< point p's entries of scaled_ are [offset_[p], offset_[p+1])
  std::vector<int> point_of_tet_;    ///< −1 for tets not guarded
  Eigen::VectorXd q_reference_;
  std::vector<double> moved_;         ///< ‖t_s − t_ref,s‖ per function (scratch)
  std::vector<double> budget_;        ///< β_s = min over the tets touching s of r_e / L_e, per function
  std::vector<int> function_offset_;  ///< function s touches the points function_points_[offset[s] .. offset[s+1])
  std::vector<int> function_points_;
  std::vector<unsigned> visited_;  ///< per point: the generation of the check that last bounded it
  unsigned generation_ = 0;
  bool valid_ = false;  ///< a reference is set
  double limit_ = 0.0;
  double energy_limit_ = model::kInfinity;
  double renew_fraction_ = 0.05;  ///< renew the reference when more tets than this fraction need evaluating
  double last_max_ = 0.0;
  int guarded_ = 0, full_checks_ = 0, checks_ = 0, tet_passes_ = 0;
  long exact_ = 0;
  double pass_seconds_ = 0.0, renew_seconds_ = 0.0;
};

}  // namespace sflsh::reduced
