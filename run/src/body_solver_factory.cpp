// The one factory of body solvers (body_solver_factory.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/run/body_solver_factory.hpp>

namespace sflsh::run {

reduced::ReducedModel make_reduced_model(const model::BodyLayer& layer, const SolverChoice& choice,
                                         const std::string& cache) {
  check_solver_choice(choice);
  return reduced::build_reduced_model(
      layer, reduced::reduced_model_options(choice.reduced_settings, choice.handles, choice.cubature, cache));
}

ReducedParts parts_of(const reduced::ReducedModel& model) { return {&model.subspace, &model.cubature}; }

BuiltSolver make_body_solver(const model::Problem& problem, const SolverChoice& choice, const model::State& initial,
                             ReducedParts parts, MPI_Comm comm) {
  BuiltSolver built;
  switch (choice.kind) {
    case SolverKind::full: {
      fullspace::FullSpaceOptions options = choice.full;
      options.integrator = choice.integrator;
      options.quasi_static = choice.quasi_static;
      auto solver = std::make_unique<fullspace::FullSpaceSolver>(problem, comm, options);
      solver->initialize(initial);
      built.full = solver.get();
      built.solver = std::move(solver);
      break;
    }
    case SolverKind::reduced: {
      require(parts.subspace && parts.cubature, "reduced solver: no reduced model was built for it");
      check_solver_choice(choice);
      reduced::ReducedOptions options = choice.reduced;
      options.integrator = choice.integrator;
      options.quasi_static = choice.quasi_static;
      options.step_tolerance = choice.newton_tolerance;
      auto solver = std::make_unique<reduced::ReducedSolver>(problem, *parts.subspace, *parts.cubature, options);
      solver->initialize(initial);
      built.reduced = solver.get();
      built.solver = std::move(solver);
      break;
    }
    case SolverKind::sundials: {
      require(!choice.quasi_static, "the SUNDIALS reference integrates the dynamics; it has no quasi-static form");
      auto solver = std::make_unique<SundialsBodySolver>(problem, choice.sundials, initial, choice.step_rate);
      built.sundials = solver.get();
      built.solver = std::move(solver);
      break;
    }
  }
  return built;
}

}  // namespace sflsh::run
