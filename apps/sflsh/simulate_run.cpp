#include "simulate_run.hpp"

namespace sflsh::app {

void add_reduced_run_options(CLI::App& cmd, BodyRunSettings& s) {
  cmd.add_option("--handles", s.handles, "Reduced: point handles inside the layer (plus the 24 bone handles)");
  cmd.add_option(
      "--cubature", s.cubature,
      "Reduced: cubature tets K (default −1 = auto: from max(200, 0.8 × coordinates), grown until the cubature sees "
      "every direction of the subspace with ≥ 1/4 of its exact rest stiffness; 0 = every tet, exact)");
  cmd.add_option("--cubature-weights", s.cubature_weights, "Reduced: nnls (training-free force matching) | voronoi")
      ->check(CLI::IsMember({"nnls", "voronoi"}));
  cmd.add_flag("--affine", s.affine, "Reduced: affine point handles (12 coordinates each instead of 3)");
  cmd.add_option(
      "--newton-tolerance", s.newton_tolerance,
      "Reduced: stop Newton when the estimated distance of every handle to the step's solution is below this [m]");
}

void add_integrator_option(CLI::App& cmd, std::string& integrator) {
  cmd.add_option("--integrator", integrator,
                 "Time integrator: bdf2 (default; second order, mild damping: keeps ≥ 95 % of the motion at 60 fps) | "
                 "newmark (trapezoidal, no numerical damping) | backward_euler (the paper's, with --mass lumped; first "
                 "order, damps a third of the motion at 60 fps); docs/integrators.md");
}

}  // namespace sflsh::app
