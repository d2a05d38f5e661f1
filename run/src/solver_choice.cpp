// The solver choice of a body run: names and checks (solver_choice.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/run/solver_choice.hpp>

#include <cmath>

namespace sflsh::run {

const char* to_string(SolverKind kind) {
  switch (kind) {
    case SolverKind::full:
      return "full";
    case SolverKind::reduced:
      return "reduced";
    case SolverKind::sundials:
      return "sundials";
  }
  return "?";
}

SolverKind parse_solver_kind(std::string_view text, std::string_view option) {
  for (SolverKind kind : {SolverKind::full, SolverKind::reduced, SolverKind::sundials})
    if (text == to_string(kind)) return kind;
  throw Error(fmt::format("{} {}: expected full, reduced or sundials", option, text));
}

SolverChoice reduced_choice(const reduced::ReducedOptions& options) {
  SolverChoice choice;
  choice.kind = SolverKind::reduced;
  choice.integrator = options.integrator;
  choice.quasi_static = options.quasi_static;
  choice.newton_tolerance = options.step_tolerance;
  choice.reduced = options;
  return choice;
}

void check_solver_choice(const SolverChoice& choice) {
  // Both bounds in every message; 10⁶ as a scene's integer keys.
  require(choice.handles >= 1 && choice.handles <= 1'000'000, "--handles must be an integer in [1, 10⁶], got {}",
          choice.handles);
  require(choice.cubature >= -1, "--cubature must be −1 (auto), 0 (every tet) or a tet count, got {}", choice.cubature);
  require(choice.newton_tolerance > 0.0 && std::isfinite(choice.newton_tolerance),
          "--newton-tolerance must be a positive length in metres, got {}", choice.newton_tolerance);
  require(choice.reduced_settings.cubature_weights == "nnls" || choice.reduced_settings.cubature_weights == "voronoi",
          "--cubature-weights {}: expected nnls or voronoi", choice.reduced_settings.cubature_weights);
}

}  // namespace sflsh::run
