#pragma once
// What one step of any solver did (the full-space solver on PETSc and the reduced model report the same
// record; the frame loop sums them per frame and summary.json lists them).
#include <string>

namespace sflsh::model {

struct StepStats {
  int newton_iterations = 0;        ///< summed over substeps
  int linear_iterations = 0;        ///< Krylov iterations (full space; 0 for dense solves)
  int factorizations = 0;           ///< Hessians factorized (reduced: ≤ newton_iterations when a factor is reused)
  int substeps = 1;                 ///< 1 unless the step had to be split
  int failed_attempts = 0;          ///< attempts rejected (divergence, NaN/Inf, failed line search, out of range)
  int projected_retries = 0;        ///< exact-Hessian attempts repeated with the PSD projection
  int fallback_preconditioner = 0;  ///< attempts repeated with CG + Jacobi after a linear-solver failure
  int preconditioner_builds = 0;    ///< preconditioners built (full space; < newton_iterations when reused)
  int truncated_solves = 0;         ///< Newton iterations whose CG stopped at negative curvature (full space)
  int potential_refinements = 0;    ///< substeps solved again because a node potential refused the result
  int startup_steps = 0;            ///< substeps a multistep integrator (BDF2) took as backward Euler
  int cubature_added = 0;           ///< tets the reduced model's guard added to its cubature (cubature_guard.hpp)
  double seconds = 0.0;             ///< wall time of the step [s]
  double function_seconds = 0.0;    ///< objective and gradient evaluations (full space) [s]
  double jacobian_seconds = 0.0;    ///< Hessian assembly (full space) [s]
  double elastic_seconds = 0.0;     ///< elastic energies, forces and Hessians (reduced: at the cubature) [s]
  double inertia_seconds = 0.0;     ///< inertia and gravity terms, node maps, predictions [s]
  double solve_seconds = 0.0;       ///< dense factorizations and solves (reduced) [s]
  double potential_seconds = 0.0;   ///< node potentials (contact): broad phase, evaluations, acceptance [s]
  double final_gradient = 0.0;      ///< ‖∇Φ‖ at the solution of the last substep [N]
  std::string converged_reason;     ///< why the last substep stopped
};

}  // namespace sflsh::model
