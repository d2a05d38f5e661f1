#pragma once
// The error-controlled reference integrator: the full-space equations of motion of problem.hpp as a
// first-order system, integrated by SUNDIALS ARKODE (ARKStep, fully implicit adaptive SDIRK, Newton with a
// sparse KLU direct solve). It is the "exact" dynamics that backward Euler (and later the reduced model)
// is measured against on small verification problems.
//
// State y = [x; w] (6N): x the unposed elastic positions (3N), w = ṗ the posed velocities (3N). With
// p_i = A_i(t) x_i + d_i(t) and the equation of motion A_iᵀ m_i (p̈_i − g) = −∇_i E(x) (problem.hpp):
//   \f[ \dot x_i = A_i^{-1}\,(w_i - \dot A_i x_i - \dot d_i), \qquad
//       \dot w_i = \frac{1}{m_i} A_i^{-T} (-\nabla_i E(x)) + g. \f]
// Consistent mass (problem.mass_kind, mass.hpp): ARKODE's mass-matrix form M_y ẏ = f with M_y = diag(I, M_w),
//   \f[ \sum_j M_{ij} \dot w_j = -A_i^{-T}\nabla_i E(x) + m_i g - \sum_{c\ \mathrm{prescribed}} M_{ic}\, a_c(t) \f]
// per axis on the free components, M_w = M ⊗ I₃ restricted to them (identity rows on prescribed components,
// ẇ = 0 there as above), a_c the prescribed posed acceleration (a difference of the prescribed velocity,
// fullspace/src/reference_mass.hpp). M_y is time-independent and factorized once per initialize by a second KLU solver;
// the lumped path is the explicit form above (M_y = I). Both obey the same constraint rules. Prescribed (Dirichlet)
// components of x take their prescribed value X + u(t) wherever x enters the forces (the state's entry is ignored), get
// ẋ = du/dt and ẇ = 0. Component-wise constraints need A_i = I (the verification problems); a node with some but not
// all components prescribed under A_i ≉ I is an error. Reported states carry the prescribed x and, on constrained
// components, the kinematic velocity ṗ = Ȧx + ḋ + Aẋ (the state's own w there is frozen at its initial value and means
// nothing).
//
// Jacobian J = ∂f/∂y (sparse CSR, pattern from the tet connectivity, built once):
//   ∂ẋ_i/∂x_i = −A_i⁻¹Ȧ_i,  ∂ẋ_i/∂w_i = A_i⁻¹,  ∂ẇ_i/∂x_j = −(1/m_i) A_i⁻ᵀ K_ij,  ∂ẇ/∂w = 0,
// (consistent mass: ∂f_w,i/∂x_j = −A_i⁻ᵀ K_ij; the Newton matrix is M_y − γJ)
// with K the elastic Hessian (exact by default) and the rows and columns of prescribed x components zero.
//
// Serial: one process, SUNDIALS serial vectors. Run it on rank 0 only / with one MPI process.
// All SUNDIALS-specific code sits in reference_integrator.cpp (SUNDIALS 7 renames parts of the API).
#include <sflsh/fullspace/model_names.hpp>
#include <sflsh/material/psd_projection.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>

namespace sflsh::fullspace {

/// Settings of the reference run.
struct ReferenceOptions {
  double rtol = 1e-6;        ///< ARKODE relative tolerance (scalar)
  double atol = 1e-9;        ///< ARKODE absolute tolerance (scalar; [m] on x, [m/s] on w)
  long max_steps = 1000000;  ///< most internal steps per advance_to call ("too much work" beyond)
  /// Order of the implicit method, 2..5, with ARKODE's default table for it: 2 SDIRK_2_1_2,
  /// 3 ARK324L2SA_DIRK_4_2_3, 4 SDIRK_5_3_4, 5 ARK548L2SA_DIRK_8_4_5. For rtol ≲ 1e-10 take 5 (a 3-cell
  /// bar to rtol 1e-12: 1163 steps at order 5, 16730 at order 4); order 2 is only for comparisons.
  int order = 4;
  double initial_step = 0.0;  ///< first step [s]; 0 lets ARKODE estimate it
  double max_step = 0.0;      ///< largest step [s]; 0 = unlimited
  double min_step = 0.0;      ///< smallest step [s]; 0 = ARKODE's default (none)
  /// The elastic Hessian in the Jacobian. Exact by default: the Jacobian only steers Newton, and the exact
  /// one keeps Newton quadratic; a projection changes no result, only the iteration counts.
  material::HessianProjection projection = material::HessianProjection::kNone;
};

/// ARKODE's counters since initialize() and the wall time spent in advance_to.
struct ReferenceStats {
  long steps = 0;             ///< accepted internal steps
  long rhs_evals = 0;         ///< evaluations of f
  long jac_evals = 0;         ///< Jacobian assemblies
  long nonlin_iters = 0;      ///< Newton iterations
  long lin_setups = 0;        ///< linear-solver setups (KLU factorizations)
  long error_test_fails = 0;  ///< steps rejected by the error test
  long conv_fails = 0;        ///< Newton convergence failures
  long mass_solves = 0;       ///< solves with the consistent mass matrix (0 with lumped masses)
  double last_step = 0.0;     ///< size of the last internal step [s]
  double seconds = 0.0;       ///< wall time in advance_to [s]
};

/// Adaptive implicit reference integration of a dynamic full-space problem (see the file comment).
/// Keeps a reference to `problem`, which must outlive the integrator and be validated (Problem::validate).
class ReferenceIntegrator {
 public:
  /// Checks the problem (dynamic, every node that is not fully prescribed has mass > 0; consistent mass: ρV per
  /// tet whose row sums are the lumped masses) and the options, and builds the Jacobian pattern (and M_y).
  /// Throws sflsh::Error on bad input.
  ReferenceIntegrator(const Problem& problem, const ReferenceOptions& options = {});
  ~ReferenceIntegrator();
  ReferenceIntegrator(const ReferenceIntegrator&) = delete;
  ReferenceIntegrator& operator=(const ReferenceIntegrator&) = delete;
  ReferenceIntegrator(ReferenceIntegrator&&) noexcept;
  ReferenceIntegrator& operator=(ReferenceIntegrator&&) noexcept;

  /// Starts (or restarts) the integration at initial.t from (initial.x, initial.w); resets the statistics.
  void initialize(const State& initial);
  /// Integrates to exactly t_out (ARKODE's stop time; no interpolation) and returns the state there.
  /// Throws sflsh::Error naming ARKODE's flag, the time reached and the reason when ARKODE gives up: too
  /// much work, repeated error-test or Newton failures (non-finite elastic forces are recoverable: ARKODE
  /// retries with a smaller step), or forcing that is not finite (node maps or prescribed values that are
  /// NaN/Inf at some time: unrecoverable, since no smaller step avoids them). The integrator must then be
  /// re-initialized.
  State advance_to(double t_out);
  /// The current time [s].
  double time() const;
  /// f(t, y) with y = [x; w] (6N), as ARKODE sees it (for tests and diagnostics): the right side of
  /// M_y ẏ = f (lumped: ẏ itself). Throws when it fails.
  Eigen::VectorXd rhs(double t, const Eigen::VectorXd& y);
  /// M_y (6N×6N): the identity with lumped masses, diag(I, M_w) with consistent ones (see the file comment).
  Eigen::SparseMatrix<double, Eigen::RowMajor> mass_matrix() const;
  /// J = ∂f/∂y at (t, y) (6N×6N, the stored pattern including explicit zeros; for tests and diagnostics).
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian(double t, const Eigen::VectorXd& y);
  const ReferenceStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh::fullspace
