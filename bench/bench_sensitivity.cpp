// Benchmark: the Young-modulus Jacobian of a reduced simulation by forward sensitivities against finite
// differences. One subject (β = 0) and motion on a layer with N material control points; the sensitivities
// give dq/dY for all 2N moduli in one run, one-sided finite differences need 2N extra simulations and as many
// rebuilds of the tet materials (SFLSH §5 does the same with 1 + 3N including the thickness).
// Usage: bench_sensitivity [--mesh coarse] [--handles 86] [--cubature -1] [--controls 84] [--frames 60]
//                          [--motion shake_hips] [--out bench_sensitivity.json]
#include "bench_options.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_sensitivity.hpp>
#include <sflsh/reduced/young_map.hpp>

#include <fmt/format.h>

#include <chrono>
#include <iostream>
#include <optional>

namespace {

using namespace sflsh;
using Clock = std::chrono::steady_clock;

struct PlainRun {
  double seconds = 0.0;
  long newton = 0;
};

PlainRun plain_run(const model::Problem& problem, const reduced::ReducedModel& model,
                   const reduced::ReducedOptions& options, int frames, double h) {
  reduced::ReducedSolver integrator(problem, model.subspace, model.cubature, options);
  integrator.initialize(model::initial_state(problem, 0.0));
  PlainRun run;
  const auto t = Clock::now();
  for (int f = 0; f < frames; ++f) run.newton += integrator.step(h).newton_iterations;
  run.seconds = seconds_since(t);
  return run;
}

struct SensitivityOptions {
  std::string mesh = "coarse", motion_name = "shake_hips", out = "bench_sensitivity.json";
  int handles = 86, cubature = -1, controls = 84, frames = 60;
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, SensitivityOptions& o) {
  CLI::App app{
      "The Young-modulus Jacobian of a reduced simulation by forward sensitivities against finite "
      "differences, for one subject (β = 0) and motion.",
      "bench_sensitivity"};
  bench::use_bench_defaults(app);
  app.add_option("--mesh", o.mesh, "Layer resolution: coarse | default | fine")
      ->check(bench::accepted_by("coarse|default|fine", meshing::parse_size_preset));
  app.add_option("--handles", o.handles, "Point handles of the reduced model");
  app.add_option("--cubature", o.cubature, "Cubature tets (0: every tet; -1: automatic)");
  app.add_option("--controls", o.controls, "Material control points N (2N Young-modulus columns)");
  app.add_option("--frames", o.frames, "Frames of 1/60 s");
  app.add_option("--motion", o.motion_name, "Procedural motion (sflsh motion list)");
  app.add_option("--out", o.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

/// The run with sensitivities: wall time and its parts [s], Newton iterations, the largest |dq/dY| [m/Pa].
struct SensitivityRun {
  double seconds = 0.0, solve = 0.0, young = 0.0, history = 0.0, hessian = 0.0, factor = 0.0, largest = 0.0;
  long newton = 0;
};

SensitivityRun sensitivity_run(const model::Problem& problem, const reduced::ReducedModel& model,
                               const Eigen::MatrixXd& W, int frames, double h) {
  reduced::SensitivityIntegrator sensitivity(problem, model.subspace, model.cubature, W);
  sensitivity.initialize(model::initial_state(problem, 0.0));
  SensitivityRun run;
  const auto t = Clock::now();
  for (int f = 0; f < frames; ++f) {
    const reduced::SensitivityStepStats s = sensitivity.step_with_sensitivity(h);
    run.solve += s.seconds;
    run.young += s.young_seconds;
    run.history += s.history_seconds;
    run.hessian += s.hessian_seconds;
    run.factor += s.solve_seconds;
    run.newton += s.step.newton_iterations;
  }
  run.seconds = seconds_since(t);
  run.largest = sensitivity.dq_dyoung().cwiseAbs().maxCoeff();
  return run;
}

/// Everything measured, with the model and the maps it was measured on.
struct Measured {
  const reduced::ReducedModel& reduced_model;
  const reduced::LayerYoungMap& map;
  double map_seconds = 0.0;
  int columns = 0;
  PlainRun plain{}, tight{};
  SensitivityRun sens{};
  double rebuild_seconds = 0.0, fd_seconds = 0.0, fd_tight_seconds = 0.0;
};

void print_table(const SensitivityOptions& o, const Measured& m) {
  const int frames = o.frames, columns = m.columns;
  std::cout << fmt::format(
      "Young-modulus Jacobian: {} mesh, {} point handles ({} coordinates), {} cubature tets, {} control points "
      "({} columns), {} frames of 1/60 s ({})\n\n",
      o.mesh, o.handles, m.reduced_model.subspace.num_dofs(), m.reduced_model.cubature.size(), m.map.num_controls(),
      columns, frames, o.motion_name);
  std::cout << fmt::format("{:<48} {:>10} {:>12} {:>10}\n", "case", "seconds", "ms/frame", "newton");
  const auto row = [&](const std::string& name, double seconds, double newton) {
    std::cout << fmt::format("{:<48} {:>10.3f} {:>12.3f} {:>10.2f}\n", name, seconds, 1e3 * seconds / frames,
                             newton / frames);
  };
  row("plain simulation (default tolerance)", m.plain.seconds, static_cast<double>(m.plain.newton));
  row("plain simulation (sensitivity tolerance)", m.tight.seconds, static_cast<double>(m.tight.newton));
  row(fmt::format("with {} sensitivity columns", columns), m.sens.seconds, static_cast<double>(m.sens.newton));
  row("  of which sensitivity work", m.sens.solve, 0.0);
  row("    dgrad/dY at the cubature points", m.sens.young, 0.0);
  row("    history (cross-time masses x S)", m.sens.history, 0.0);
  row("    exact Hessian", m.sens.hessian, 0.0);
  row("    Cholesky + 2N-column solve", m.sens.factor, 0.0);
  row(fmt::format("finite differences: {} × (plain + rebuild)", columns), m.fd_seconds, 0.0);
  row(fmt::format("finite differences: {} × (tight + rebuild)", columns), m.fd_tight_seconds, 0.0);
  std::cout << fmt::format(
      "\nrebuild of the tet materials {:.4f} s; Young maps (once per subject) {:.3f} s; speed-up over finite "
      "differences {:.1f}× (default tolerance), {:.1f}× (same tolerance); max |dq/dY| {:.3e} m/Pa\n",
      m.rebuild_seconds, m.map_seconds, m.fd_seconds / m.sens.seconds, m.fd_tight_seconds / m.sens.seconds,
      m.sens.largest);
}

void write_results(const SensitivityOptions& o, const Measured& m) {
  write_json(o.out, {{"benchmark", "sensitivity"},
                     {"mesh", o.mesh},
                     {"point_handles", o.handles},
                     {"coordinates", m.reduced_model.subspace.num_dofs()},
                     {"cubature", m.reduced_model.cubature.size()},
                     {"control_points", m.map.num_controls()},
                     {"columns", m.columns},
                     {"frames", o.frames},
                     {"motion", o.motion_name},
                     {"plain_seconds", m.plain.seconds},
                     {"plain_tight_seconds", m.tight.seconds},
                     {"sensitivity_seconds", m.sens.seconds},
                     {"sensitivity_work_seconds", m.sens.solve},
                     {"sensitivity_young_seconds", m.sens.young},
                     {"sensitivity_history_seconds", m.sens.history},
                     {"sensitivity_hessian_seconds", m.sens.hessian},
                     {"sensitivity_factor_solve_seconds", m.sens.factor},
                     {"rebuild_seconds", m.rebuild_seconds},
                     {"map_seconds", m.map_seconds},
                     {"finite_difference_seconds", m.fd_seconds},
                     {"finite_difference_tight_seconds", m.fd_tight_seconds},
                     {"speedup", m.fd_seconds / m.sens.seconds},
                     {"speedup_same_tolerance", m.fd_tight_seconds / m.sens.seconds}});
}

/// The layer and the reduced model, the maps, the plain runs, the run with sensitivities, the rebuild; the table
/// and the JSON.
void run_benchmark(const SensitivityOptions& o) {
  logger()->set_level(spdlog::level::warn);
  const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  model::BodyLayerOptions layer_options;
  layer_options.size = meshing::parse_size_preset(o.mesh);
  const double h = 1.0 / 60.0;
  const body::Motion motion = body::make_procedural_motion(o.motion_name, 60.0, o.frames + 2);
  const model::BodyLayer layer =
      model::build_body_layer(model, body::Betas::Zero(), motion, nullptr, o.controls, layer_options);
  reduced::ReducedModelOptions options;
  options.point_handles = o.handles;
  options.cubature = o.cubature;
  const reduced::ReducedModel reduced_model = reduced::build_reduced_model(layer, options);

  // The maps, once per subject (the fit reuses them across iterations).
  auto t = Clock::now();
  const reduced::LayerYoungMap map(layer);
  const Eigen::MatrixXd W = map.tet_map(reduced_model.cubature.tets);
  const double map_seconds = seconds_since(t);
  Measured m{reduced_model, map};
  m.map_seconds = map_seconds;
  m.columns = 2 * map.num_controls();

  // Plain simulations: the integrator's defaults (what a finite-difference Jacobian would run) and the
  // tolerance that sensitivities use.
  m.plain = plain_run(layer.problem, reduced_model, reduced::ReducedOptions{}, o.frames, h);
  m.tight = plain_run(layer.problem, reduced_model, reduced::sensitivity_solver_options(), o.frames, h);

  // With sensitivities.
  m.sens = sensitivity_run(layer.problem, reduced_model, W, o.frames, h);

  // Finite differences: 2N extra simulations, each after a rebuild of the tet materials.
  model::Problem perturbed = layer.problem;
  Eigen::MatrixX2d young = map.control_young();
  young(0, 0) *= 1.0 + 1e-4;
  const int rebuilds = 3;
  t = Clock::now();
  for (int k = 0; k < rebuilds; ++k) map.set_control_young(young, perturbed);
  m.rebuild_seconds = seconds_since(t) / rebuilds;
  m.fd_seconds = m.columns * (m.plain.seconds + m.rebuild_seconds);
  m.fd_tight_seconds = m.columns * (m.tight.seconds + m.rebuild_seconds);

  print_table(o, m);
  write_results(o, m);
  std::cout << "wrote " << o.out << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  SensitivityOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  try {
    run_benchmark(o);
  } catch (const std::exception& e) {
    std::cerr << "bench_sensitivity: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
