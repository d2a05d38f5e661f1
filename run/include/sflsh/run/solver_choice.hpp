#pragma once
// Which solver runs a body and how: the one typed description every entry point fills (the command line's
// options, the Python module's keywords, a scene's [[body]] keys) and the project's one set of run defaults
// (run_defaults.hpp, docs/body_run.md). make_body_solver (body_solver_factory.hpp) turns it into a model::BodySolver.
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/reduced/reduced_settings.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/run/run_defaults.hpp>

#include <string>
#include <string_view>

namespace sflsh::run {

enum class SolverKind {
  full,      ///< the full-space solver on PETSc (fullspace_solver.hpp)
  reduced,   ///< handles + cubature (reduced_solver.hpp)
  sundials,  ///< the error-controlled ARKODE reference (reference_integrator.hpp), one process
};
const char* to_string(SolverKind kind);
/// "full" | "reduced" | "sundials"; a one-line error naming `option` otherwise.
SolverKind parse_solver_kind(std::string_view text, std::string_view option);

/// The solver of one body run.
struct SolverChoice {
  SolverKind kind = SolverKind::full;
  model::Integrator integrator = model::kDefaultIntegrator;  ///< full and reduced (SUNDIALS chooses its own steps)
  bool quasi_static = false;                                 ///< drop inertia: equilibrium per step
  /// Reduced model: handles and cubature of the model (make_reduced_model), Newton's step tolerance [m].
  int handles = kDefaultHandles;
  int cubature = kDefaultCubature;
  reduced::ReducedSettings reduced_settings;  ///< cubature weights, affine handles
  double newton_tolerance = kDefaultNewtonTolerance;
  /// SUNDIALS: the frame loop's fps × substeps [1/s], whose grid the steps end on (sundials_body_solver.hpp); 0: none.
  double step_rate = 0.0;
  /// The rest of each solver's options (preconditioner, threads, tracking root, coupled unknowns, a local patch,
  /// sensitivities' records, ARKODE's tolerances …). make_body_solver overrides their integrator, quasi_static and
  /// (reduced) step tolerance with the fields above, so these are never set twice.
  fullspace::FullSpaceOptions full;
  reduced::ReducedOptions reduced;
  fullspace::ReferenceOptions sundials;
};

/// The reduced solver with these options (their integrator, quasi_static and step tolerance become the choice's).
SolverChoice reduced_choice(const reduced::ReducedOptions& options);

/// Checks the choice; the messages name the command-line options (--handles, --cubature, --newton-tolerance, …).
void check_solver_choice(const SolverChoice& choice);

}  // namespace sflsh::run
