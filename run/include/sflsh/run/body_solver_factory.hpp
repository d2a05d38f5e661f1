#pragma once
// The one place a body's solver is built (docs/body_run.md): the full-space solver, the reduced model on its
// subspace and cubature, or the SUNDIALS reference behind an adaptor whose step advances to t + h, each behind
// model::BodySolver and initialized at the run's first state. simulate, sweep, compare, tradeoff, groundtruth,
// the fit's dynamics cases, scenes and Python's Simulation get their solvers here.
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/run/solver_choice.hpp>
#include <sflsh/run/sundials_body_solver.hpp>

#include <mpi.h>

#include <memory>
#include <string>

namespace sflsh::run {

/// The reduced model of `choice` (handles, cubature, weights, affine) on a layer; `cache` empty: the default cache.
reduced::ReducedModel make_reduced_model(const model::BodyLayer& layer, const SolverChoice& choice,
                                         const std::string& cache);

/// A built solver: the interface every frame loop steps, and the concrete solver for what only it offers
/// (checkpoints, coupling, sensitivities). Exactly one of full, reduced, sundials is set.
struct BuiltSolver {
  std::unique_ptr<model::BodySolver> solver;
  fullspace::FullSpaceSolver* full = nullptr;
  reduced::ReducedSolver* reduced = nullptr;
  SundialsBodySolver* sundials = nullptr;
  model::BodySolver& operator*() const { return *solver; }
  model::BodySolver* operator->() const { return solver.get(); }
};

/// The subspace and cubature a reduced solver runs on (they must outlive it).
struct ReducedParts {
  const reduced::Subspace* subspace = nullptr;
  const reduced::Cubature* cubature = nullptr;
};
/// The parts of a reduced model (its subspace and cubature).
ReducedParts parts_of(const reduced::ReducedModel& model);

/// Builds the solver of `choice` for `problem` (which, with `reduced`'s parts, must outlive it) and initializes it
/// at `initial`. `reduced` is needed for SolverKind::reduced only; `comm` is the full-space solver's communicator.
/// Throws sflsh::Error with a one-line message on a bad choice.
BuiltSolver make_body_solver(const model::Problem& problem, const SolverChoice& choice, const model::State& initial,
                             ReducedParts reduced = {}, MPI_Comm comm = MPI_COMM_WORLD);

}  // namespace sflsh::run
