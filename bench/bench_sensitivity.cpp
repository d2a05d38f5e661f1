// Benchmark: the Young-modulus Jacobian of a reduced simulation by forward sensitivities against finite
// differences. One subject (β = 0) and motion on a layer with N material control points; the sensitivities
// give dq/dY for all 2N moduli in one run, one-sided finite differences need 2N extra simulations and as many
// rebuilds of the tet materials (SFLSH §5 does the same with 1 + 3N including the thickness).
// Usage: bench_sensitivity [--mesh coarse] [--handles 86] [--cubature -1] [--controls 84] [--frames 60]
//                          [--motion shake_hips] [--out bench_sensitivity.json]
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
#include <cstring>
#include <iostream>

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

}  // namespace

int main(int argc, char** argv) {
  std::string mesh = "coarse", motion_name = "shake_hips", out = "bench_sensitivity.json";
  int handles = 86, cubature = -1, controls = 84, frames = 60;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--mesh") == 0)
      mesh = argv[i + 1];
    else if (std::strcmp(argv[i], "--handles") == 0)
      handles = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--cubature") == 0)
      cubature = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--controls") == 0)
      controls = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--frames") == 0)
      frames = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--motion") == 0)
      motion_name = argv[i + 1];
    else if (std::strcmp(argv[i], "--out") == 0)
      out = argv[i + 1];
    else {
      std::cerr << "bench_sensitivity: unknown option " << argv[i] << "\n";
      return 2;
    }
  }
  try {
    logger()->set_level(spdlog::level::warn);
    const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
    model::BodyLayerOptions layer_options;
    layer_options.size = meshing::parse_size_preset(mesh);
    const double h = 1.0 / 60.0;
    const body::Motion motion = body::make_procedural_motion(motion_name, 60.0, frames + 2);
    const model::BodyLayer layer =
        model::build_body_layer(model, body::Betas::Zero(), motion, nullptr, controls, layer_options);
    reduced::ReducedModelOptions options;
    options.point_handles = handles;
    options.cubature = cubature;
    const reduced::ReducedModel reduced_model = reduced::build_reduced_model(layer, options);

    // The maps, once per subject (the fit reuses them across iterations).
    auto t = Clock::now();
    const reduced::LayerYoungMap map(layer);
    const Eigen::MatrixXd W = map.tet_map(reduced_model.cubature.tets);
    const double map_seconds = seconds_since(t);
    const int columns = 2 * map.num_controls();

    // Plain simulations: the integrator's defaults (what a finite-difference Jacobian would run) and the
    // tolerance that sensitivities use.
    const PlainRun plain = plain_run(layer.problem, reduced_model, reduced::ReducedOptions{}, frames, h);
    const PlainRun tight = plain_run(layer.problem, reduced_model, reduced::sensitivity_solver_options(), frames, h);

    // With sensitivities.
    reduced::SensitivityIntegrator sensitivity(layer.problem, reduced_model.subspace, reduced_model.cubature, W);
    sensitivity.initialize(model::initial_state(layer.problem, 0.0));
    double sens_solve = 0.0, sens_young = 0.0, sens_history = 0.0, sens_hessian = 0.0, sens_factor = 0.0;
    long sens_newton = 0;
    t = Clock::now();
    for (int f = 0; f < frames; ++f) {
      const reduced::SensitivityStepStats s = sensitivity.step(h);
      sens_solve += s.seconds;
      sens_young += s.young_seconds;
      sens_history += s.history_seconds;
      sens_hessian += s.hessian_seconds;
      sens_factor += s.solve_seconds;
      sens_newton += s.step.newton_iterations;
    }
    const double sens_seconds = seconds_since(t);
    const double largest = sensitivity.dq_dyoung().cwiseAbs().maxCoeff();

    // Finite differences: 2N extra simulations, each after a rebuild of the tet materials.
    model::Problem perturbed = layer.problem;
    Eigen::MatrixX2d young = map.control_young();
    young(0, 0) *= 1.0 + 1e-4;
    const int rebuilds = 3;
    t = Clock::now();
    for (int k = 0; k < rebuilds; ++k) map.set_control_young(young, perturbed);
    const double rebuild_seconds = seconds_since(t) / rebuilds;
    const double fd_seconds = columns * (plain.seconds + rebuild_seconds);
    const double fd_tight_seconds = columns * (tight.seconds + rebuild_seconds);

    std::cout << fmt::format(
        "Young-modulus Jacobian: {} mesh, {} point handles ({} coordinates), {} cubature tets, {} control points "
        "({} columns), {} frames of 1/60 s ({})\n\n",
        mesh, handles, reduced_model.subspace.num_dofs(), reduced_model.cubature.size(), map.num_controls(), columns,
        frames, motion_name);
    std::cout << fmt::format("{:<48} {:>10} {:>12} {:>10}\n", "case", "seconds", "ms/frame", "newton");
    const auto row = [&](const std::string& name, double seconds, double newton) {
      std::cout << fmt::format("{:<48} {:>10.3f} {:>12.3f} {:>10.2f}\n", name, seconds, 1e3 * seconds / frames,
                               newton / frames);
    };
    row("plain simulation (default tolerance)", plain.seconds, static_cast<double>(plain.newton));
    row("plain simulation (sensitivity tolerance)", tight.seconds, static_cast<double>(tight.newton));
    row(fmt::format("with {} sensitivity columns", columns), sens_seconds, static_cast<double>(sens_newton));
    row("  of which sensitivity work", sens_solve, 0.0);
    row("    dgrad/dY at the cubature points", sens_young, 0.0);
    row("    history (cross-time masses x S)", sens_history, 0.0);
    row("    exact Hessian", sens_hessian, 0.0);
    row("    Cholesky + 2N-column solve", sens_factor, 0.0);
    row(fmt::format("finite differences: {} × (plain + rebuild)", columns), fd_seconds, 0.0);
    row(fmt::format("finite differences: {} × (tight + rebuild)", columns), fd_tight_seconds, 0.0);
    std::cout << fmt::format(
        "\nrebuild of the tet materials {:.4f} s; Young maps (once per subject) {:.3f} s; speed-up over finite "
        "differences {:.1f}× (default tolerance), {:.1f}× (same tolerance); max |dq/dY| {:.3e} m/Pa\n",
        rebuild_seconds, map_seconds, fd_seconds / sens_seconds, fd_tight_seconds / sens_seconds, largest);
    write_json(out, {{"benchmark", "sensitivity"},
                     {"mesh", mesh},
                     {"point_handles", handles},
                     {"coordinates", reduced_model.subspace.num_dofs()},
                     {"cubature", reduced_model.cubature.size()},
                     {"control_points", map.num_controls()},
                     {"columns", columns},
                     {"frames", frames},
                     {"motion", motion_name},
                     {"plain_seconds", plain.seconds},
                     {"plain_tight_seconds", tight.seconds},
                     {"sensitivity_seconds", sens_seconds},
                     {"sensitivity_work_seconds", sens_solve},
                     {"sensitivity_young_seconds", sens_young},
                     {"sensitivity_history_seconds", sens_history},
                     {"sensitivity_hessian_seconds", sens_hessian},
                     {"sensitivity_factor_solve_seconds", sens_factor},
                     {"rebuild_seconds", rebuild_seconds},
                     {"map_seconds", map_seconds},
                     {"finite_difference_seconds", fd_seconds},
                     {"finite_difference_tight_seconds", fd_tight_seconds},
                     {"speedup", fd_seconds / sens_seconds},
                     {"speedup_same_tolerance", fd_tight_seconds / sens_seconds}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_sensitivity: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
