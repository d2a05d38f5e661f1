#pragma once
// The reduced model's time step: the full-space incremental potential of model/time_integrator.hpp restricted to
// x = x_D + (B ⊗ I₃) q,
//   Φ(q) = 1/(2ĥ²)(p(q) − p̃)ᵀM(p(q) − p̃) − gᵀMp(q) + Σ_c ω_c V_c Ψ(F_c(q)) + U(p(q)),
// with the integrator's ĥ and p̃ (backward Euler, BDF2 or Newmark) from the posed history of the inertia nodes
// (reduced_inertia.hpp), M lumped or consistent. Φ is the sum of the reduced terms (reduced_terms.hpp): inertia
// and gravity exactly quadratic in q, elasticity by cubature with κ per cubature tet, node potentials (contact)
// on their candidates of each substep. Minimized by dense Newton (Cholesky of the 3S × 3S Hessian) with a
// backtracking (Armijo) line search on Φ; the converged substep advances the history (model::advance_history).
// Robustness as in the full-space solver: the exact Hessian first, a failed attempt (indefinite Hessian, failed
// line search, non-finite or over-cap state) is repeated with PSD-projected dP/dF, then as 2, 4, … 2^max_halvings
// substeps, then a one-line sflsh::Error naming the time and the reason; the state and the history are never
// left half-updated. BDF2 starts (and restarts after a step grew more than twofold) as backward Euler
// (StepStats::startup_steps); Newmark needs p̈ at the start, computed in the subspace (reduced_history.hpp)
// unless the initial state carries it.
// Single-threaded on purpose: crowds parallelize over bodies.
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/model/step_stats.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/reduced/coupled_term.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/cubature_guard.hpp>
#include <sflsh/reduced/local_basis.hpp>
#include <sflsh/reduced/local_elastic.hpp>
#include <sflsh/reduced/newton_factor.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/root_tracking.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <Eigen/Cholesky>

#include <memory>
#include <string>
#include <vector>

namespace sflsh::reduced {

struct ReducedOptions {
  model::Integrator integrator = model::Integrator::backward_euler;  ///< model/time_integrator.hpp
  bool quasi_static = false;                                         ///< drop inertia (gravity still acts through mass)
  int max_halvings = 6;
  int max_newton = 30;
  double gradient_rtol = 1e-8;  ///< ‖∇Φ‖ ≤ rtol·‖∇Φ₀‖ …
  double gradient_atol = 1e-9;  ///< … or ≤ atol [N]
  /// … or the distance left to the step's solution, estimated from the contraction of the last two full Newton
  /// steps (ρ/(1 − ρ)‖Δq‖∞, ‖Δq‖∞ after the first), below this [m]. 10 µm is 0.1–0.3 % of the σ the
  /// motions produce (docs/reduced.md "Newton iterations"); sensitivities solve tighter (1e-9 m).
  double step_tolerance = 1e-5;
  /// Reuse the Cholesky factor of an earlier Hessian (from earlier iterations or steps of the same ĥ and
  /// projection) while it keeps reducing ‖∇Φ‖ by at least `refresh_ratio` per iteration; M/ĥ² dominates
  /// the dynamic Hessian, so it changes slowly and a refactorization (the dense O(n³) part) is rarely due.
  /// The minimizer is the same; only the path to it changes. Off: plain Newton.
  bool reuse_factorization = true;
  double refresh_ratio = 0.25;
  bool exact_hessian_first = true;
  bool use_predictor = true;  ///< start Newton from the extrapolated q when its Φ is lower than at q_n
  int predictor_order = 2;    ///< 1: q_n + h q̇_n; 2: + ½h² q̈_n (backward differences)
  /// Keep the converged substeps of the last step (last_substeps()), for forward sensitivities.
  bool record_substeps = false;
  /// Guard the tets outside the cubature (cubature_guard.hpp): a tet whose Fung exponent x = 2Ψ₀/c passes
  /// `guard_exponent` at a converged substep joins the cubature (weight 1, its volume taken from the nearest point's
  /// weight) and the substep is solved again, at most `max_enlargements` times per substep.
  /// A tet also joins when its Fung energy passes `guard_energy` [J] (its exponent limit is then
  /// ln(1 + 2 guard_energy / (c V)), cubature_guard.hpp): at 25 alone an unseen tet of 1 cm³ at c = 1250 Pa may
  /// hold 4·10⁷ J, and default runs left tets of 7.5 kJ–39 MJ outside the cubature (docs/reduced.md, "Robust
  /// cubature").
  bool guard = true;
  double guard_exponent = 25.0;
  double guard_energy = 1.0;
  int max_enlargements = 8;
  /// A tracking root (root_tracking.hpp): the six root coordinates join q in the Newton solve. Off: the skeleton
  /// follows its motion exactly (prescribed), bit for bit as before.
  RootTrackingOptions root;
  /// Unknowns solved in the same Newton solve (coupled_system.hpp: e.g. free rigid objects on the skin), not
  /// owned; x = [q; y], or [q; θ; τ; y] with a tracking root. Null: none.
  CoupledSystem* coupled = nullptr;
  /// A local patch for contact (local_basis.hpp), not owned: the solver's subspace becomes [B  Φ], q = [t; e], and the
  /// tets the local functions touch are integrated exactly (local_elastic.hpp); the cubature must then be fitted
  /// without them (reduced_model.hpp, cubature_outside). Null: the handles alone.
  const LocalBasis* local = nullptr;
};

/// One converged substep of an accepted step: from t0 over dt to coordinates q.
struct ReducedSubstep {
  double t0 = 0.0;
  double dt = 0.0;
  Eigen::VectorXd q;
  /// The cubature weights the substep was solved with, one per tet of cubature() in order (the guard appends tets
  /// and moves weight, so a substep may see fewer points than the cubature has later).
  std::vector<double> cubature_weights;
};

class ReducedSolver final : public model::BodySolver {
 public:
  /// The problem, subspace and cubature must outlive the integrator; the problem must be validated and its
  /// constrained nodes fully constrained (all three components) with zero basis rows.
  ReducedSolver(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                const ReducedOptions& options = {});
  ReducedSolver(const ReducedSolver&) = delete;  // the terms hold references to the members
  ReducedSolver& operator=(const ReducedSolver&) = delete;

  /// Sets the state from a full one: x projected onto the subspace by least squares on the active nodes; w, and
  /// a (Newmark), p_previous, w_previous (BDF2) when the state has them, taken at the inertia nodes. Newmark
  /// without a computes p̈ in the subspace (reduced_history.hpp); BDF2 without a previous step starts as
  /// backward Euler.
  void initialize(const model::State& state);
  /// Advances by h [s]; throws sflsh::Error (state unchanged) when even 2^max_halvings substeps fail.
  model::StepStats step(double h) override;

  double time() const { return t_; }
  const Eigen::VectorXd& q() const { return q_; }
  /// The full-space state: x = x_D + (B ⊗ I₃) q on every node; w from the history at the inertia nodes and the
  /// skinned velocity of the prescribed motion elsewhere. Newmark also returns a, BDF2 p_previous, w_previous and
  /// h_previous (once a step was taken), from the history at the inertia nodes and the prescribed motion elsewhere.
  model::State full_state() const;
  model::State current_state() const override { return full_state(); }
  /// The node positions x = x_D + (B ⊗ I₃) q alone [m] (3N): what the skin displacement and σ need, without the
  /// velocities and the prescribed motion's node maps that full_state() evaluates.
  Eigen::VectorXd positions() const override;
  /// The posed history of the inertia nodes (ReducedInertia::inertia_nodes()).
  const model::PosedHistory& history() const { return history_; }
  const ReducedInertia& inertia() const { return inertia_; }
  /// Φ's elastic part at the current state (cubature) [J].
  double elastic_energy() const;
  /// The subspace q lives in: the handles' [B], or [B  Φ] with local bumps (options.local).
  const Subspace& subspace() const { return subspace_; }
  /// The handles' coordinates in q (3S; the cubature's); the bumps' follow.
  Eigen::Index handle_dofs() const { return base_subspace_.num_dofs(); }
  /// The cubature in use: the model's, plus the tets the guard added (cubature_added()).
  const Cubature& cubature() const { return cubature_; }
  /// Tets the guard added to the cubature since construction.
  int cubature_added() const { return added_; }
  /// The guard (nullptr when options.guard is off).
  const CubatureGuard* guard() const { return guard_.get(); }
  const ReducedOptions& options() const { return options_; }
  /// Whether the root tracks its motion (options.root.enabled), and its deviation r = (θ [rad], τ [m]) from the
  /// motion's pose now (zero with a prescribed skeleton).
  bool tracking() const { return options_.root.enabled; }
  Vector6d root() const { return deviation_.head<6>(); }
  /// The whole deviation r = (θ, τ, φ_1, …, φ_J) [rad, m, rad] now; the tracked joints' φ_j follow the root's six.
  const Eigen::VectorXd& deviation() const { return deviation_; }
  /// The skeleton (its tracked joints and bones) and the deviation's frame now, to deviate any blended point.
  const SkeletonDeviation& skeleton() const { return skeleton_; }
  DeviationFrame deviation_frame() const;
  /// The root deviation now as p ↦ R p + t in the problem's posed frame (identity with a prescribed skeleton).
  void root_transform(Eigen::Matrix3d& R, Eigen::Vector3d& t) const;
  /// The root's tracking spring and damper per coordinate (θ then τ) [N·m/rad, N/m; N·m·s/rad, N·s/m].
  Vector6d root_stiffness() const { return tracking_stiffness_.head<6>(); }
  Vector6d root_damping() const { return tracking_damping_.head<6>(); }
  /// Per coordinate of the deviation: spring [N·m/rad | N/m] and damper; per tracked joint: the limit φ_max [rad],
  /// its stiffness [N·m/rad] and the moment of inertia I_j of what the joint carries [kg·m²].
  const Eigen::VectorXd& tracking_stiffness() const { return tracking_stiffness_; }
  const Eigen::VectorXd& tracking_damping() const { return tracking_damping_; }
  const Eigen::VectorXd& joint_limits() const { return joint_limit_; }
  const Eigen::VectorXd& joint_limit_stiffness() const { return joint_limit_stiffness_; }
  const Eigen::VectorXd& joint_inertia() const { return joint_inertia_; }
  /// The substeps of the last successful step(), in order (empty unless options.record_substeps).
  const std::vector<ReducedSubstep>& last_substeps() const { return substeps_; }

  /// What a step changes: time, q, the predictor's rates, the tracking skeleton's deviation and the centres it turns
  /// about, the posed histories. The robustness ladder puts it back before it tries a step again; a checkpoint holds
  /// it with the reusable factorization.
  struct StepState {
    double t = 0.0;
    Eigen::VectorXd q, rate, rate_previous;
    double rate_dt = 0.0;
    int rate_steps = 0;
    Eigen::VectorXd deviation;
    DeviationPose pose;
    model::PosedHistory history, carried_history;
  };
  /// The whole state a step starts from (the step state and the reusable factorization), so that a step can be
  /// solved again from the same start with other potentials' obstacles (the scene's body-contact exchanges). The
  /// cubature the guard grew is kept on restore (it only grows).
  struct Checkpoint {
    StepState state;
    NewtonFactor factor;
    bool factor_valid = false;
    double factor_h = 0.0;
    material::HessianProjection factor_projection = material::HessianProjection::kNone;
  };
  Checkpoint checkpoint() const;
  /// Puts the state of checkpoint() back: the same step then gives the same result bit for bit.
  void restore(const Checkpoint& checkpoint);

 private:
  class Ladder;  ///< the solver on the model's robustness ladder (model/step_ladder.hpp)
  /// Copies the step state out and back; the posed histories only `with_histories` (several vectors per node).
  void save_state(StepState& state, bool with_histories) const;
  void restore_state(const StepState& state, bool with_histories);
  /// x_D at t: the rest state with the attached nodes' prescribed values. Without drives that is the rest state at
  /// every t: a reference to it, with no pass over the nodes; with drives `storage` is filled and returned.
  const Eigen::VectorXd& prescribed_state(double t, Eigen::VectorXd& storage) const;
  /// One substep from the current state; `startup` counts a BDF2 substep taken as backward Euler
  /// (reduced_solver_substep.cpp: the steps below).
  bool solve_substep(double t0, double dt, material::HessianProjection projection, model::StepStats& stats,
                     std::string& reason, int& startup);
  struct Substep;  ///< what one substep's steps share: times, targets, the start and the sum of terms
  enum class GuardOutcome { clear, enlarged, failed };
  void set_substep_targets(Substep& s, model::StepStats& stats);
  void begin_substep_potentials(Substep& s, model::StepStats& stats);
  void collect_substep_terms(Substep& s, model::StepStats& stats) const;
  /// The start of Newton: x_start or the predicted state, whichever has the lower Φ.
  bool start_iterate(const Substep& s, Eigen::VectorXd& q, double& phi, std::string& reason) const;
  bool substep_gradient(const Substep& s, const Eigen::VectorXd& q, Eigen::VectorXd& gradient,
                        std::string& reason) const;
  /// The Hessian of Φ at q, factorized into factor_.
  bool factorize(const Substep& s, const Eigen::VectorXd& q, Eigen::MatrixXd& hessian, model::StepStats& stats,
                 std::string& reason);
  /// Newton with backtracking on Φ, reusing the factor while it contracts the gradient.
  bool newton(const Substep& s, Eigen::VectorXd& q, double phi, model::StepStats& stats, std::string& reason);
  GuardOutcome check_guard(const Substep& s, const Eigen::VectorXd& q, int& enlargements, model::StepStats& stats,
                           std::string& reason);
  /// Whether the node potentials and the coupled system accept q (settled: the substep ends), stiffened themselves
  /// (refine: solved again), or refuse it for good (failed, with the potential's reason: the ladder goes on).
  enum class ContactOutcome { settled, refine, failed };
  ContactOutcome contact_settled(const Substep& s, const Eigen::VectorXd& q, int refinement, model::StepStats& stats,
                                 std::string& reason);
  void commit_substep(const Substep& s, const Eigen::VectorXd& q, model::StepStats& stats, int& startup);
  /// Newmark's p̈ at the inertia nodes for the current q and time (zero without inertia).
  Eigen::VectorXd initial_acceleration() const;
  /// Adds the guard's violations to the cubature (reduced_solver_guard.cpp).
  void enlarge_cubature(const std::vector<GuardViolation>& over, double t);
  /// Tracking root: the attached nodes' skinned positions at t (x_D the prescribed state) and the pivot c(t).
  void carried_posed(double t, const Eigen::VectorXd& x_prescribed, meshing::RowMatrixX3d& p) const;
  Eigen::Vector3d root_pivot(double t, const meshing::RowMatrixX3d& carried) const;
  /// The pivot and the tracked joints' centres at t.
  DeviationPose deviation_pose(double t, const meshing::RowMatrixX3d& carried) const;
  /// The springs, dampers and limits of the deviation from the layer at the start (carried: the attached nodes).
  void setup_tracking_springs(const meshing::RowMatrixX3d& carried);
  void setup_root();
  void setup_coupled();

  const model::Problem& problem_;
  const Subspace& base_subspace_;  ///< the handles' functions B (the cubature's)
  Subspace local_subspace_;        ///< [B  Φ] with local bumps, else empty
  const Subspace& subspace_;       ///< the subspace of q: one of the two
  Cubature cubature_;              ///< the model's cubature, grown by the guard
  ReducedOptions options_;
  CubatureElastic elastic_;
  std::unique_ptr<CubatureGuard> guard_;
  int added_ = 0;
  ReducedInertia inertia_;
  ReducedPotentials potentials_;
  ReducedElasticTerm elastic_term_;
  ReducedInertiaTerm inertia_term_;
  ReducedGravityTerm gravity_term_;
  ReducedPotentialTerm potential_term_;
  bool has_drives_ = false;
  Eigen::VectorXd rest_state_;  ///< X (3N), the prescribed state of every t without drives
  // The reusable factorization and what it was computed for.
  NewtonFactor factor_;  ///< dense, or by the Schur complement on a local patch
  bool factor_valid_ = false;
  double factor_h_ = 0.0;  ///< ĥ of the factorized Hessian
  material::HessianProjection factor_projection_ = material::HessianProjection::kNone;

  double t_ = 0.0;
  Eigen::VectorXd q_, q_rate_;       ///< q and its backward difference (for the predictor)
  Eigen::VectorXd q_rate_previous_;  ///< the backward difference one step earlier
  double rate_dt_ = 0.0;             ///< the step of q_rate_ [s]
  int rate_steps_ = 0;               ///< substeps behind q_rate_ (0, 1, ≥ 2)
  model::PosedHistory history_;      ///< posed kinematics of the inertia nodes
  std::vector<ReducedSubstep> substeps_;
  // Tracking skeleton (options.root.enabled): x = [q; r], r = (θ, τ, φ_1, …) at offset 3S.
  std::vector<int> carried_;          ///< nodes with mass that only the root moves (not inertia nodes)
  std::vector<double> carried_mass_;  ///< their lumped masses [kg]
  model::PosedHistory carried_history_;
  SkeletonDeviation skeleton_;
  Eigen::VectorXd deviation_ = Vector6d::Zero();  ///< r = (θ, τ, φ_1, …, φ_J)
  DeviationPose pose_;                            ///< the centres at t_
  Eigen::VectorXd tracking_stiffness_ = Vector6d::Zero(), tracking_damping_ = Vector6d::Zero();
  Eigen::VectorXd joint_limit_, joint_limit_stiffness_, joint_inertia_;
  std::unique_ptr<HeadTerm> elastic_head_, gravity_head_;
  std::unique_ptr<RootInertiaTerm> root_inertia_term_;
  std::unique_ptr<RootTrackingTerm> root_tracking_term_;
  std::unique_ptr<RootPotentialTerm> root_potential_term_;
  // Coupled system (options.coupled): x = [q; y], y at offset 3S; the q terms on the head of x.
  std::unique_ptr<CoupledTerm> coupled_term_;
  std::unique_ptr<HeadTerm> inertia_head_, potential_head_;
  // Local bumps (options.local): their exact energy, on the head [t; e] of x with a root or a coupled system.
  std::unique_ptr<LocalElasticTerm> local_term_;
  std::unique_ptr<HeadTerm> local_head_;
};

}  // namespace sflsh::reduced
