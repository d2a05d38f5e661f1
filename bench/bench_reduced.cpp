// Benchmark: frames per second of the reduced model for one body on one thread, and for a crowd of bodies
// with random shapes (each its own shape-dependent layer and material) and per-body time offsets on T
// threads (parallel over bodies, as the paper's Fig. 1), with the per-frame breakdown: cubature forces and
// Hessians, inertia (node maps, mass Hessian), dense solve, and skinning of the output surface.
// A frame = one step of 1/60 s + the posed skin of the whole body (what a renderer needs). The one-body case runs
// once per integrator × mass of the lists (fps, Newton iterations and factorizations per frame each); the crowd
// uses the first of both.
// The guard of the tets outside the cubature (cubature_guard.hpp) is part of "elastic"; its share is the "(guard)"
// column. Usage: bench_reduced [--mesh coarse] [--handles 86] [--cubature 200] [--frames 120] [--crowd 25]
//                      [--step-tolerance M] [--gradient-rtol R] [--refresh-ratio R] [--predictor-order 1|2]
//                      [--guard 0|1] [--guard-exponent X] [--guard-energy J]
//                      [--threads 2] [--motion shake_hips] [--integrators backward_euler,bdf2,newmark]
//                      [--masses lumped,consistent] [--out bench_reduced.json]
#include "bench_options.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <random>

namespace {

using namespace sflsh;
using Clock = std::chrono::steady_clock;

struct Body {
  model::BodyLayer layer;
  reduced::ReducedModel model;
  std::unique_ptr<reduced::ReducedSolver> integrator;
  double t0 = 0.0;
};

struct Breakdown {
  double step = 0, elastic = 0, inertia = 0, solve = 0, output = 0;
  long newton = 0, factorizations = 0, startup = 0, failed = 0, substeps = 0;
  void add(const model::StepStats& s) {
    step += s.seconds;
    elastic += s.elastic_seconds;
    inertia += s.inertia_seconds;
    solve += s.solve_seconds;
    newton += s.newton_iterations;
    factorizations += s.factorizations;
    startup += s.startup_steps;
    failed += s.failed_attempts + s.projected_retries;
    substeps += s.substeps;
  }
};

std::unique_ptr<Body> make_body(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion,
                                double t0, const model::BodyLayerOptions& layer_options,
                                const reduced::ReducedModelOptions& options,
                                const reduced::ReducedOptions& solver_options) {
  auto b = std::make_unique<Body>();
  b->layer = model::build_body_layer(model, beta, motion, nullptr, 12, layer_options);
  b->model = reduced::build_reduced_model(b->layer, options);
  b->integrator =
      std::make_unique<reduced::ReducedSolver>(b->layer.problem, b->model.subspace, b->model.cubature, solver_options);
  b->integrator->initialize(model::initial_state(b->layer.problem, t0));
  b->t0 = t0;
  return b;
}

/// One frame of one body: a step and the posed skin surface.
void advance(Body& b, double h, Breakdown& breakdown) {
  breakdown.add(b.integrator->step(h));
  const auto t = Clock::now();
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(b.layer.problem.rest.data(), b.layer.problem.num_dofs());
  b.model.subspace.add_displacement(b.integrator->q(), x);
  const meshing::RowMatrixX3d posed = b.layer.posed_surface(x, b.integrator->time());
  if (!posed.allFinite()) throw std::runtime_error("non-finite posed surface");
  breakdown.output += seconds_since(t);
}

struct Arguments {
  std::string mesh = "coarse", motion_name = "shake_hips", out = "bench_reduced.json";
  // The defaults of every body run (model::kDefaultIntegrator, kDefaultMassKind); the paper's pair with
  // --integrators backward_euler --masses lumped.
  std::string integrator_list{model::to_string(model::kDefaultIntegrator)};
  std::string mass_list{model::to_string(model::kDefaultMassKind)};
  int handles = 86, cubature = 200, frames = 120, crowd = 25, threads = 2;
  reduced::ReducedOptions tuned;  // solver settings from the command line
};

/// Reads the command line into `a`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_arguments(int argc, char** argv, Arguments& a) {
  CLI::App app{
      "Frames per second of the reduced model for one body on one thread (per integrator × mass) and for a "
      "crowd of bodies with random shapes on T threads, with the per-frame breakdown.",
      "bench_reduced"};
  bench::use_bench_defaults(app);
  reduced::ReducedOptions& tuned = a.tuned;
  app.add_option("--mesh", a.mesh, "Layer resolution: coarse | default | fine")
      ->check(bench::accepted_by("coarse|default|fine", meshing::parse_size_preset));
  app.add_option("--handles", a.handles, "Point handles of the reduced model");
  app.add_option("--cubature", a.cubature, "Cubature tets (0: every tet; -1: automatic)");
  app.add_option("--frames", a.frames, "Frames of 1/60 s per run");
  app.add_option("--crowd", a.crowd, "Bodies of the crowd (0: no crowd)");
  app.add_option("--threads", a.threads, "Threads of the crowd (parallel over bodies)");
  app.add_option("--motion", a.motion_name, "Procedural motion (sflsh motion list)");
  app.add_option("--integrators", a.integrator_list,
                 "Time integrators of the one-body runs, comma-separated: backward_euler | bdf2 | newmark (the crowd "
                 "uses the first)");
  app.add_option("--masses", a.mass_list,
                 "Mass kinds of the one-body runs, comma-separated: lumped | consistent (the crowd uses the first)");
  app.add_option("--step-tolerance", tuned.step_tolerance,
                 "Newton stops when the distance left to the step's solution is below this [m]");
  app.add_option("--gradient-rtol", tuned.gradient_rtol, "Newton stops when ‖∇Φ‖ ≤ rtol·‖∇Φ₀‖");
  app.add_option("--refresh-ratio", tuned.refresh_ratio,
                 "Refactor the Hessian when ‖∇Φ‖ falls by less than this per iteration");
  app.add_option("--predictor-order", tuned.predictor_order, "Predictor: 1 (q + h q̇) | 2 (+ ½h² q̈)");
  app.add_option_function<int>(
      "--guard", [&tuned](int on) { tuned.guard = on != 0; },
      "Guard the tets outside the cubature: 1 (default) | 0 (off)");
  app.add_option("--guard-exponent", tuned.guard_exponent,
                 "Guard: a tet whose Fung exponent passes this joins the cubature");
  app.add_option("--guard-energy", tuned.guard_energy, "Guard: a tet whose Fung energy passes this joins [J]");
  app.add_option("--out", a.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

/// What the runs share: the body model, the motion, the layer and reduced-model options, the integrators and masses.
struct Setup {
  body::BodyModel model;
  body::Motion motion;
  model::BodyLayerOptions layer_options;
  reduced::ReducedModelOptions options;
  std::vector<model::Integrator> integrators;
  std::vector<model::MassKind> masses;
};

constexpr double kStep = 1.0 / 60.0;
constexpr int kOffsetFrames = 60;  // crowd members start up to 1 s apart

Setup make_setup(const Arguments& a) {
  Setup setup{body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz"),
              body::make_procedural_motion(a.motion_name, 60.0, a.frames + kOffsetFrames + 2),
              {},
              {},
              {},
              {}};
  setup.layer_options.size = meshing::parse_size_preset(a.mesh);
  setup.options.point_handles = a.handles;
  setup.options.cubature = a.cubature;
  for (const std::string& name : bench::split_list(a.integrator_list))
    setup.integrators.push_back(model::parse_integrator(name, "--integrators"));
  for (const std::string& name : bench::split_list(a.mass_list))
    setup.masses.push_back(model::parse_mass_kind(name, "--masses"));
  require(!setup.integrators.empty() && !setup.masses.empty(),
          "--integrators and --masses need at least one entry each");
  return setup;
}

/// One body on one thread for one integrator and mass.
struct Case {
  model::Integrator integrator;
  model::MassKind mass;
  Breakdown breakdown;
  double wall = 0.0;
  int guard_full_checks = 0, guard_checks = 0, guard_passes = 0, cubature_added = 0;
  double guard_seconds = 0.0;  ///< per-tet passes and renewals [s]
};

/// Every integrator × mass on one body; `coordinates` receives the subspace's size.
std::vector<Case> run_one_body_cases(const Arguments& a, const Setup& setup, int& coordinates) {
  std::vector<Case> cases;
  for (model::MassKind mass : setup.masses) {
    for (model::Integrator integrator : setup.integrators) {
      model::BodyLayerOptions case_layer = setup.layer_options;
      case_layer.mass = mass;
      reduced::ReducedOptions solver_options = a.tuned;
      solver_options.integrator = integrator;
      auto body =
          make_body(setup.model, body::Betas::Zero(), setup.motion, 0.0, case_layer, setup.options, solver_options);
      coordinates = body->model.subspace.num_dofs();
      Case c{integrator, mass, {}, 0.0};
      const auto t = Clock::now();
      for (int f = 0; f < a.frames; ++f) advance(*body, kStep, c.breakdown);
      c.wall = seconds_since(t);
      if (const reduced::CubatureGuard* guard = body->integrator->guard()) {
        c.guard_full_checks = guard->full_checks();
        c.guard_checks = guard->checks();
        c.guard_passes = guard->tet_passes();
        c.guard_seconds = guard->pass_seconds() + guard->renew_seconds();
      }
      c.cubature_added = body->integrator->cubature_added();
      cases.push_back(c);
    }
  }
  return cases;
}

struct CrowdResult {
  Breakdown total;  ///< summed over the bodies
  double wall = 0.0, build_seconds = 0.0;
};

/// The crowd: random shapes (β ~ N(0, 1), clamped to ±2.5) and time offsets, parallel over bodies, with the first
/// integrator and mass.
CrowdResult run_crowd(const Arguments& a, const Setup& setup) {
  model::BodyLayerOptions crowd_layer = setup.layer_options;
  crowd_layer.mass = setup.masses.front();
  reduced::ReducedOptions crowd_solver = a.tuned;
  crowd_solver.integrator = setup.integrators.front();
  std::mt19937 rng(20231212);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_int_distribution<int> offset(0, kOffsetFrames);
  std::vector<std::unique_ptr<Body>> bodies;
  CrowdResult result;
  const auto t_build = Clock::now();
  for (int b = 0; b < a.crowd; ++b) {
    body::Betas beta;
    for (int k = 0; k < beta.size(); ++k) beta[k] = std::clamp(normal(rng), -2.5, 2.5);
    bodies.push_back(
        make_body(setup.model, beta, setup.motion, offset(rng) / 60.0, crowd_layer, setup.options, crowd_solver));
  }
  result.build_seconds = seconds_since(t_build);
  std::vector<Breakdown> per_body(bodies.size());
  tbb::task_arena arena(a.threads);
  const auto t_crowd = Clock::now();
  for (int f = 0; f < a.frames; ++f)
    arena.execute([&] {
      tbb::parallel_for(std::size_t{0}, bodies.size(), [&](std::size_t b) { advance(*bodies[b], kStep, per_body[b]); });
    });
  result.wall = seconds_since(t_crowd);
  for (const Breakdown& b : per_body) {
    result.total.step += b.step;
    result.total.elastic += b.elastic;
    result.total.inertia += b.inertia;
    result.total.solve += b.solve;
    result.total.output += b.output;
    result.total.newton += b.newton;
    result.total.factorizations += b.factorizations;
  }
  return result;
}

double ms(double seconds, double count) { return 1e3 * seconds / count; }

/// Prints the one-body rows; returns them as JSON.
nlohmann::json report_one_body_cases(const std::vector<Case>& cases, int frames) {
  nlohmann::json combinations = nlohmann::json::array();
  for (const Case& c : cases) {
    const Breakdown& b = c.breakdown;
    const std::string label = fmt::format("1 body, {}, {}", model::to_string(c.integrator), model::to_string(c.mass));
    std::cout << fmt::format(
        "{:<36} {:>8.1f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>8.2f} {:>8.2f} {:>12}\n", label,
        frames / c.wall, ms(c.wall, frames), ms(b.elastic, frames), ms(c.guard_seconds, frames), ms(b.inertia, frames),
        ms(b.solve, frames), ms(b.output, frames), static_cast<double>(b.newton) / frames,
        static_cast<double>(b.factorizations) / frames, &c == &cases.front() ? "30 (1 thr)" : "");
    combinations.push_back({{"integrator", model::to_string(c.integrator)},
                            {"mass", model::to_string(c.mass)},
                            {"threads", 1},
                            {"fps", frames / c.wall},
                            {"ms_per_frame", ms(c.wall, frames)},
                            {"elastic_ms", ms(b.elastic, frames)},
                            {"inertia_ms", ms(b.inertia, frames)},
                            {"solve_ms", ms(b.solve, frames)},
                            {"output_ms", ms(b.output, frames)},
                            {"newton_per_frame", static_cast<double>(b.newton) / frames},
                            {"factorizations_per_frame", static_cast<double>(b.factorizations) / frames},
                            {"startup_steps", b.startup},
                            {"failed_attempts", b.failed},
                            {"substeps", b.substeps},
                            {"guard",
                             {{"ms_per_frame", ms(c.guard_seconds, frames)},
                              {"checks", c.guard_checks},
                              {"per_tet_passes", c.guard_passes},
                              {"renewals", c.guard_full_checks},
                              {"cubature_added", c.cubature_added}}}});
  }
  return combinations;
}

/// Prints the crowd row (none for --crowd 0); returns it as JSON (null for --crowd 0).
nlohmann::json report_crowd(const Arguments& a, const Setup& setup, const CrowdResult& crowd) {
  const double n = static_cast<double>(a.frames) * a.crowd;
  const Breakdown& total = crowd.total;
  const double crowd_fps = a.frames / crowd.wall;
  if (a.crowd > 0)
    std::cout << fmt::format(
        "{:<36} {:>8.1f} {:>10.3f} {:>10.3f} {:>10} {:>10.3f} {:>10.3f} {:>10.3f} {:>8.2f} {:>8.2f} {:>12}\n",
        fmt::format("{} bodies, {} threads", a.crowd, a.threads), crowd_fps, ms(crowd.wall, a.frames),
        ms(total.elastic, n), "", ms(total.inertia, n), ms(total.solve, n), ms(total.output, n),
        static_cast<double>(total.newton) / n, static_cast<double>(total.factorizations) / n, "1.2 (1 thr)");
  std::cout << fmt::format(
      "\n(ms per frame; newton and factor: Newton iterations and Hessian factorizations per frame; the crowd runs {} "
      "with {} masses, its breakdown columns are per body and frame; crowd built in {:.1f} s)\n",
      model::to_string(setup.integrators.front()), model::to_string(setup.masses.front()), crowd.build_seconds);
  if (a.crowd == 0) return nlohmann::json(nullptr);
  return {{"bodies", a.crowd},
          {"threads", a.threads},
          {"fps", crowd_fps},
          {"ms_per_frame", ms(crowd.wall, a.frames)},
          {"elastic_ms_per_body", ms(total.elastic, n)},
          {"inertia_ms_per_body", ms(total.inertia, n)},
          {"solve_ms_per_body", ms(total.solve, n)},
          {"output_ms_per_body", ms(total.output, n)},
          {"build_seconds", crowd.build_seconds},
          {"paper_fps", 1.2}};
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (const std::optional<int> status = parse_arguments(argc, argv, a)) return *status;
  try {
    logger()->set_level(spdlog::level::warn);
    const Setup setup = make_setup(a);
    int coordinates = 0;
    const std::vector<Case> cases = run_one_body_cases(a, setup, coordinates);
    const CrowdResult crowd = run_crowd(a, setup);

    std::cout << fmt::format(
        "reduced model: {} mesh, {} point handles ({} coordinates), {} cubature tets, {} frames of 1/60 s\n\n", a.mesh,
        a.handles, coordinates, a.cubature, a.frames);
    std::cout << fmt::format("{:<36} {:>8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>8} {:>8} {:>12}\n", "case",
                             "fps", "ms/frame", "elastic", "(guard)", "inertia", "solve", "output", "newton", "factor",
                             "paper fps");
    const nlohmann::json combinations = report_one_body_cases(cases, a.frames);
    const nlohmann::json crowd_json = report_crowd(a, setup, crowd);
    const Breakdown& one = cases.front().breakdown;
    const double one_wall = cases.front().wall;
    write_json(a.out, {{"benchmark", "reduced"},
                       {"mesh", a.mesh},
                       {"point_handles", a.handles},
                       {"coordinates", coordinates},
                       {"cubature", a.cubature},
                       {"frames", a.frames},
                       {"one_body",
                        {{"threads", 1},
                         {"integrator", model::to_string(setup.integrators.front())},
                         {"mass", model::to_string(setup.masses.front())},
                         {"fps", a.frames / one_wall},
                         {"ms_per_frame", ms(one_wall, a.frames)},
                         {"elastic_ms", ms(one.elastic, a.frames)},
                         {"inertia_ms", ms(one.inertia, a.frames)},
                         {"solve_ms", ms(one.solve, a.frames)},
                         {"output_ms", ms(one.output, a.frames)},
                         {"newton_per_frame", static_cast<double>(one.newton) / a.frames},
                         {"paper_fps", 30.0}}},
                       {"one_body_cases", combinations},
                       {"crowd", crowd_json}});
    std::cout << "wrote " << a.out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_reduced: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
