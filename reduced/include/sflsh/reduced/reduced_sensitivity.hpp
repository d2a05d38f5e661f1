#pragma once
// Forward sensitivities of the reduced backward-Euler trajectory with respect to the Young moduli of the
// material's control points (beyond SFLSH §5, which differentiates σ by one-sided finite differences over
// 1 + 3N simulations). Each converged (sub)step n → n+1 of size h solves ∇Φ(q_{n+1}; q_n, q_{n−1}, Y) = 0
// (reduced_solver.hpp), so by the implicit-function theorem S = dq/dY obeys
//   H(q_{n+1}) S_{n+1} = −(∂G/∂Y + ∂G/∂q_n S_n + ∂G/∂q_{n−1} S_{n−1}),
// with H the exact (unprojected) Hessian of Φ at the converged q_{n+1}, factorized afresh. The history
// enters only through the prediction p̃ = p_n + h w_n, w_n = (p_n − p_{n−1})/h_prev with p_n = z_n + A_n B q_n:
//   dp̃ = (1 + r) A_n B S_n − r A_{n−1} B S_{n−1},  r = h/h_prev,
//   ∂c/∂(history) S = −(1/h²) [(1 + r) M(t_{n+1}, t_n) S_n − r M(t_{n+1}, t_{n−1}) S_{n−1}]
// (M: ReducedInertia::cross_mass). The predictor only changes Newton's start, not the minimizer. The
// elastic part: ∂G/∂Y_i = Σ_c W_ci ω_c V_c B_cᵀ vec(∂P/∂Y)_c for both moduli (young_derivative.hpp,
// young_map.hpp). The initial state does not depend on Y: S_0 = 0, w_0 given. Substeps are steps of their own
// size. Where H is not positive definite at a converged state the trajectory is not differentiable there
// and the step throws instead of returning numbers. With a consistent mass, M(t, t') sums M_ij over pairs of
// active nodes: the targets p̃_j of their attached neighbours do not depend on Y. Backward Euler only: the
// constructor refuses BDF2 and Newmark (their targets depend on more of the history).
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/reduced/rest_geometry_derivative.hpp>

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <vector>

namespace sflsh::reduced {

/// The integrator options used with sensitivities: the plain ones with Newton driven to round-off, because
/// an unconverged q_{n+1} makes S (and a finite-difference check of it) only as good as ‖∇Φ‖:
/// ‖∇Φ‖ ≤ 1e-12·‖∇Φ₀‖ or ≤ 1e-11 N, or a full step below 1e-12 m (docs/reduced.md, "Sensitivities").
ReducedOptions sensitivity_solver_options(ReducedOptions base = {});

/// S = H⁻¹ rhs by Cholesky of H (the sensitivity solve of one substep ending at t [s]). Throws sflsh::Error when
/// H or rhs is not finite, when H is not positive definite (the converged state is no strict minimum: dq/dY
/// is not defined), or when the solution is not finite.
Eigen::MatrixXd solve_step_sensitivity(const Eigen::MatrixXd& hessian, const Eigen::MatrixXd& rhs, double t);

struct SensitivityStepStats {
  model::StepStats step;         ///< the integrator's own step
  double seconds = 0.0;          ///< the sensitivity work (all of the below)
  double young_seconds = 0.0;    ///< ∂∇Φ/∂Y at the cubature points
  double history_seconds = 0.0;  ///< cross-time masses and their products with S_n, S_{n−1}
  double hessian_seconds = 0.0;  ///< the exact Hessian
  double solve_seconds = 0.0;    ///< Cholesky and the 2N-column solve
  int factorizations = 0;        ///< one per substep
};

/// Rest-geometry columns of the sensitivities (rest_geometry_derivative.hpp): dX per parameter and the depth field.
struct RestDirections {
  std::vector<meshing::RowMatrixX3d> directions;  ///< dX_j (N × 3 each) [m per unit of parameter j]
  Eigen::VectorXd depth;                          ///< the retargeter's harmonic depth per node
};

/// Also a model::BodySolver, so that the frame loop (model/frame_loop.hpp) steps it like any body solver; step()
/// then keeps the sensitivity statistics of the last step (last_sensitivity_stats()).
class SensitivityIntegrator final : public model::BodySolver {
 public:
  /// @param[in] young_map  W (cubature.size() × N): Y of cubature tet c = Σ_i W(c, i) Y_i, for both Y_t and Y_n
  ///                       (young_map.hpp); the problem's tet materials must be the ones these Y give.
  /// The problem, subspace and cubature must outlive the integrator. `options` are used as given (pass
  /// sensitivity_solver_options() for derivatives that a finite-difference check can reproduce);
  /// record_substeps is switched on.
  /// With `rest` (not null; it must outlive the integrator) H columns dq/dX·dX_j follow the 2N Young ones.
  SensitivityIntegrator(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                        Eigen::MatrixXd young_map, const ReducedOptions& options = sensitivity_solver_options(),
                        const RestDirections* rest = nullptr);

  /// The state (as ReducedSolver::initialize) and S = 0.
  void initialize(const model::State& state);
  /// W rows for tets the guard adds to the cubature during the run (reduced_solver_guard.cpp): each substep's
  /// sensitivity is then taken on the cubature that substep was solved with, so dq/dY is the derivative of the
  /// run the plain solver makes (its cubature grows at the same states). Without them a grown cubature throws.
  using YoungRows = std::function<Eigen::MatrixXd(const std::vector<int>& tets)>;
  void set_young_rows(YoungRows rows) { young_rows_ = std::move(rows); }

  /// One step of ReducedSolver followed by the sensitivity solves of its substeps. Throws sflsh::Error
  /// (naming the time) when the step fails, when H is not positive definite at a converged state, when a
  /// sensitivity is not finite, or when the guard grew the cubature and there are no young rows; the
  /// sensitivities are then invalid until initialize().
  SensitivityStepStats step_with_sensitivity(double h);
  /// step_with_sensitivity(h) through the body-solver interface: its solver statistics.
  model::StepStats step(double h) override;
  const SensitivityStepStats& last_sensitivity_stats() const { return last_; }
  model::State current_state() const override { return integrator_.current_state(); }
  Eigen::VectorXd positions() const override { return integrator_.positions(); }

  double time() const { return integrator_.time(); }
  const Eigen::VectorXd& q() const { return integrator_.q(); }
  /// dq/dY (3S × 2N) [m/Pa]: columns Y_t of controls 0..N−1, then Y_n of 0..N−1 (physical moduli, before any
  /// stiffness scale — the scale sits in W); then, with rest directions, dq/dX·dX_j (3S × H) [m per unit].
  const Eigen::MatrixXd& dq_dyoung() const { return sensitivity_; }
  int num_controls() const { return static_cast<int>(young_map_.cols()); }
  const ReducedSolver& integrator() const { return integrator_; }

  /// ∂G/∂Y (3S × 2N) of the elastic gradient at coordinates q (public for tests).
  Eigen::MatrixXd elastic_gradient_dyoung(const Eigen::VectorXd& q) const;

 private:
  void substep_sensitivity(const ReducedSubstep& substep, SensitivityStepStats& stats);
  /// Brings the cubature points, their weights, W and the rest-geometry points to the substep's cubature.
  void follow_cubature(const std::vector<double>& weights, double t);

  const model::Problem& problem_;
  ReducedSolver integrator_;
  CubatureElastic elastic_;
  ReducedInertia inertia_;
  Eigen::MatrixXd young_map_;
  YoungRows young_rows_;
  std::vector<double> weights_;                   ///< the cubature weights elastic_ holds
  std::unique_ptr<RestGeometryDerivative> rest_;  ///< rest-geometry columns (null without)
  bool inertia_on_ = false;
  bool has_drives_ = false;
  bool valid_ = false;
  // S at the last two states and their times (the history the prediction depends on).
  Eigen::MatrixXd sensitivity_, previous_;
  double t_current_ = 0.0, t_previous_ = 0.0;
  bool has_previous_ = false;
  SensitivityStepStats last_;
};

/// The outputs at frames 0..frames: q and dq/dY per frame (frame 0 is the initial state, S = 0).
struct SensitivityResult {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> q;
  std::vector<Eigen::MatrixXd> dq_dyoung;  ///< 3S × 2N per frame [m/Pa]
  double seconds = 0.0;                    ///< wall time of the run
  double sensitivity_seconds = 0.0;        ///< of which the sensitivity solves
  long newton_iterations = 0;
};

/// Runs `frames` steps of h [s] from `start` with sensitivities (a one-off SensitivityIntegrator).
SensitivityResult simulate_with_sensitivities(const model::Problem& problem, const Subspace& subspace,
                                              const Cubature& cubature, const Eigen::MatrixXd& young_map,
                                              const model::State& start, double h, int frames,
                                              const ReducedOptions& options = sensitivity_solver_options());

}  // namespace sflsh::reduced
