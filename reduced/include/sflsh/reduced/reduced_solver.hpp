#pragma once
// Backward Euler for the reduced model: the full-space incremental potential (physics.md §5, Kane et al.
// 2000) restricted to x = x_D + (B ⊗ I₃) q,
//   Φ(q) = Σ_i m_i/(2h²) |p_i(q) − p̃_i|² − Σ_i m_i gᵀp_i(q) + Σ_c ω_c V_c Ψ(F_c(q)),   p̃ = p_n + h w_n,
// minimized by dense Newton (Cholesky of the 3S × 3S Hessian) with a backtracking (Armijo) line search on Φ.
// The inertia part is exactly quadratic (reduced_inertia.hpp), the elastic part comes from the cubature
// (cubature_elastic.hpp) with κ per cubature tet. Robustness as in the full-space solver: the exact
// Hessian first, a failed attempt (indefinite Hessian, failed line search, non-finite or over-cap
// state) is repeated with PSD-projected dP/dF, then as 2, 4, … 2^max_halvings substeps, then a one-line
// sflsh::Error naming the time and the reason; the state is never left half-updated.
// Node potentials of the problem (contact, reduced_potentials.hpp) join Φ on their candidates of each substep.
// Single-threaded on purpose: crowds parallelize over bodies.
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>
#include <sflsh/reduced/subspace.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/model/step_stats.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <Eigen/Cholesky>

#include <string>
#include <vector>

namespace sflsh::reduced {

struct ReducedOptions {
  model::Integrator integrator = model::Integrator::backward_euler;   ///< time_integrator.hpp
  bool quasi_static = false;   ///< drop inertia (gravity still acts through mass)
  int max_halvings = 6;
  int max_newton = 30;
  double gradient_rtol = 1e-8;     ///< ‖∇Φ‖ ≤ rtol·‖∇Φ₀‖ …
  double gradient_atol = 1e-9;     ///< … or ≤ atol [N]
  double step_tolerance = 1e-8;    ///< or a full Newton step with ‖Δq‖∞ below this [m]
  /// Reuse the Cholesky factor of an earlier Hessian (from earlier iterations or steps of the same h and
  /// projection) while it keeps reducing ‖∇Φ‖ by at least `refresh_ratio` per iteration; M/h² dominates
  /// the dynamic Hessian, so it changes slowly and a refactorization (the dense O(n³) part) is rarely due.
  /// The minimizer is the same; only the path to it changes. Off: plain Newton.
  bool reuse_factorization = true;
  double refresh_ratio = 0.25;
  bool exact_hessian_first = true;
  bool use_predictor = true;       ///< start Newton from q_n + h q̇_n when its Φ is lower than at q_n
  /// Keep the converged substeps of the last step (last_substeps()), for forward sensitivities.
  bool record_substeps = false;
};

/// One converged substep of an accepted step: from t0 over dt to coordinates q.
struct ReducedSubstep {
  double t0 = 0.0;
  double dt = 0.0;
  Eigen::VectorXd q;
};


class ReducedSolver final : public model::BodySolver {
 public:
  /// The problem, subspace and cubature must outlive the integrator; the problem must be validated and its
  /// constrained nodes fully constrained (all three components) with zero basis rows.
  ReducedSolver(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                       const ReducedOptions& options = {});

  /// Sets the state from a full one (x projected onto the subspace by least squares on the active nodes,
  /// w taken at the active nodes).
  void initialize(const model::State& state);
  /// Advances by h [s]; throws sflsh::Error (state unchanged) when even 2^max_halvings substeps fail.
  model::StepStats step(double h) override;

  double time() const { return t_; }
  const Eigen::VectorXd& q() const { return q_; }
  /// The full-space state: x = x_D + (B ⊗ I₃) q on every node; w from the steps at the active nodes and the
  /// skinned velocity ẋ of the prescribed motion elsewhere.
  model::State full_state() const;
  model::State current_state() const override { return full_state(); }
  /// Φ's elastic part at the current state (cubature) [J].
  double elastic_energy() const;
  const Subspace& subspace() const { return subspace_; }
  const Cubature& cubature() const { return cubature_; }
  const ReducedOptions& options() const { return options_; }
  /// The substeps of the last successful step(), in order (empty unless options.record_substeps).
  const std::vector<ReducedSubstep>& last_substeps() const { return substeps_; }

 private:
  struct Attempt;
  Eigen::VectorXd prescribed_state(double t) const;
  bool solve_substep(double t0, double dt, material::HessianProjection projection, model::StepStats& stats, std::string& reason);

  const model::Problem& problem_;
  const Subspace& subspace_;
  const Cubature& cubature_;
  ReducedOptions options_;
  CubatureElastic elastic_;
  ReducedInertia inertia_;
  ReducedPotentials potentials_;
  bool has_drives_ = false;
  // The reusable factorization and what it was computed for.
  Eigen::LLT<Eigen::MatrixXd> factor_;
  bool factor_valid_ = false;
  double factor_h_ = 0.0;
  material::HessianProjection factor_projection_ = material::HessianProjection::kNone;

  double t_ = 0.0;
  Eigen::VectorXd q_, q_rate_;            ///< q and its backward difference (for the predictor)
  meshing::RowMatrixX3d p_, w_;           ///< posed positions and velocities of the active nodes
  std::vector<ReducedSubstep> substeps_;
};

}  // namespace sflsh::reduced
