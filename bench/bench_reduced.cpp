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
#include <cstring>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>

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

/// The entries of a comma-separated list.
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

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

}  // namespace

int main(int argc, char** argv) {
  std::string mesh = "coarse", motion_name = "shake_hips", out = "bench_reduced.json";
  // The defaults of every body run (model::kDefaultIntegrator, kDefaultMassKind); the paper's pair with
  // --integrators backward_euler --masses lumped.
  std::string integrator_list(model::to_string(model::kDefaultIntegrator)),
      mass_list(model::to_string(model::kDefaultMassKind));
  int handles = 86, cubature = 200, frames = 120, crowd = 25, threads = 2;
  reduced::ReducedOptions tuned;  // solver settings from the command line
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--mesh") == 0)
      mesh = argv[i + 1];
    else if (std::strcmp(argv[i], "--handles") == 0)
      handles = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--cubature") == 0)
      cubature = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--frames") == 0)
      frames = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--crowd") == 0)
      crowd = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--threads") == 0)
      threads = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--motion") == 0)
      motion_name = argv[i + 1];
    else if (std::strcmp(argv[i], "--integrators") == 0)
      integrator_list = argv[i + 1];
    else if (std::strcmp(argv[i], "--masses") == 0)
      mass_list = argv[i + 1];
    else if (std::strcmp(argv[i], "--out") == 0)
      out = argv[i + 1];
    else if (std::strcmp(argv[i], "--step-tolerance") == 0)
      tuned.step_tolerance = std::stod(argv[i + 1]);
    else if (std::strcmp(argv[i], "--gradient-rtol") == 0)
      tuned.gradient_rtol = std::stod(argv[i + 1]);
    else if (std::strcmp(argv[i], "--refresh-ratio") == 0)
      tuned.refresh_ratio = std::stod(argv[i + 1]);
    else if (std::strcmp(argv[i], "--predictor-order") == 0)
      tuned.predictor_order = std::stoi(argv[i + 1]);
    else if (std::strcmp(argv[i], "--guard-exponent") == 0)
      tuned.guard_exponent = std::stod(argv[i + 1]);
    else if (std::strcmp(argv[i], "--guard-energy") == 0)
      tuned.guard_energy = std::stod(argv[i + 1]);
    else if (std::strcmp(argv[i], "--guard") == 0)
      tuned.guard = std::stoi(argv[i + 1]) != 0;
    else {
      std::cerr << "bench_reduced: unknown option " << argv[i] << "\n";
      return 2;
    }
  }
  try {
    logger()->set_level(spdlog::level::warn);
    const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
    model::BodyLayerOptions layer_options;
    layer_options.size = meshing::parse_size_preset(mesh);
    reduced::ReducedModelOptions options;
    options.point_handles = handles;
    options.cubature = cubature;
    const double h = 1.0 / 60.0;
    const int offset_frames = 60;  // crowd members start up to 1 s apart
    const body::Motion motion = body::make_procedural_motion(motion_name, 60.0, frames + offset_frames + 2);

    std::vector<model::Integrator> integrators;
    for (const std::string& name : split_list(integrator_list))
      integrators.push_back(model::parse_integrator(name, "--integrators"));
    std::vector<model::MassKind> masses;
    for (const std::string& name : split_list(mass_list)) masses.push_back(model::parse_mass_kind(name, "--masses"));
    require(!integrators.empty() && !masses.empty(), "--integrators and --masses need at least one entry each");

    // One body, one thread, per integrator × mass.
    struct Case {
      model::Integrator integrator;
      model::MassKind mass;
      Breakdown breakdown;
      double wall = 0.0;
      int guard_full_checks = 0, guard_checks = 0, guard_passes = 0, cubature_added = 0;
      double guard_seconds = 0.0;  ///< per-tet passes and renewals [s]
    };
    std::vector<Case> cases;
    int coordinates = 0;
    for (model::MassKind mass : masses) {
      for (model::Integrator integrator : integrators) {
        model::BodyLayerOptions case_layer = layer_options;
        case_layer.mass = mass;
        reduced::ReducedOptions solver_options = tuned;
        solver_options.integrator = integrator;
        auto body = make_body(model, body::Betas::Zero(), motion, 0.0, case_layer, options, solver_options);
        coordinates = body->model.subspace.num_dofs();
        Case c{integrator, mass, {}, 0.0};
        const auto t = Clock::now();
        for (int f = 0; f < frames; ++f) advance(*body, h, c.breakdown);
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
    const Breakdown& one = cases.front().breakdown;
    const double one_wall = cases.front().wall;
    model::BodyLayerOptions crowd_layer = layer_options;
    crowd_layer.mass = masses.front();
    reduced::ReducedOptions crowd_solver = tuned;
    crowd_solver.integrator = integrators.front();
    // The crowd: random shapes (β ~ N(0, 1), clamped to ±2.5) and time offsets, parallel over bodies.
    std::mt19937 rng(20231212);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::uniform_int_distribution<int> offset(0, offset_frames);
    std::vector<std::unique_ptr<Body>> bodies;
    const auto t_build = Clock::now();
    for (int b = 0; b < crowd; ++b) {
      body::Betas beta;
      for (int k = 0; k < beta.size(); ++k) beta[k] = std::clamp(normal(rng), -2.5, 2.5);
      bodies.push_back(make_body(model, beta, motion, offset(rng) / 60.0, crowd_layer, options, crowd_solver));
    }
    const double build_seconds = seconds_since(t_build);
    std::vector<Breakdown> per_body(bodies.size());
    tbb::task_arena arena(threads);
    const auto t_crowd = Clock::now();
    for (int f = 0; f < frames; ++f)
      arena.execute([&] {
        tbb::parallel_for(std::size_t{0}, bodies.size(), [&](std::size_t b) { advance(*bodies[b], h, per_body[b]); });
      });
    const double crowd_wall = seconds_since(t_crowd);
    Breakdown total;
    for (const Breakdown& b : per_body) {
      total.step += b.step;
      total.elastic += b.elastic;
      total.inertia += b.inertia;
      total.solve += b.solve;
      total.output += b.output;
      total.newton += b.newton;
      total.factorizations += b.factorizations;
    }

    const double one_fps = frames / one_wall, crowd_fps = frames / crowd_wall;
    const auto ms = [&](double s, double n) { return 1e3 * s / n; };
    std::cout << fmt::format(
        "reduced model: {} mesh, {} point handles ({} coordinates), {} cubature tets, {} frames of 1/60 s\n\n", mesh,
        handles, coordinates, cubature, frames);
    std::cout << fmt::format("{:<36} {:>8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>8} {:>8} {:>12}\n", "case",
                             "fps", "ms/frame", "elastic", "(guard)", "inertia", "solve", "output", "newton", "factor",
                             "paper fps");
    nlohmann::json combinations = nlohmann::json::array();
    for (const Case& c : cases) {
      const Breakdown& b = c.breakdown;
      const std::string label = fmt::format("1 body, {}, {}", model::to_string(c.integrator), model::to_string(c.mass));
      std::cout << fmt::format(
          "{:<36} {:>8.1f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>10.3f} {:>8.2f} {:>8.2f} {:>12}\n",
          label, frames / c.wall, ms(c.wall, frames), ms(b.elastic, frames), ms(c.guard_seconds, frames),
          ms(b.inertia, frames), ms(b.solve, frames), ms(b.output, frames), static_cast<double>(b.newton) / frames,
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
    const double n = static_cast<double>(frames) * crowd;
    if (crowd > 0)  // --crowd 0: no crowd row (nothing was run)
      std::cout << fmt::format(
          "{:<36} {:>8.1f} {:>10.3f} {:>10.3f} {:>10} {:>10.3f} {:>10.3f} {:>10.3f} {:>8.2f} {:>8.2f} {:>12}\n",
          fmt::format("{} bodies, {} threads", crowd, threads), crowd_fps, ms(crowd_wall, frames), ms(total.elastic, n),
          "", ms(total.inertia, n), ms(total.solve, n), ms(total.output, n), static_cast<double>(total.newton) / n,
          static_cast<double>(total.factorizations) / n, "1.2 (1 thr)");
    std::cout << fmt::format(
        "\n(ms per frame; newton and factor: Newton iterations and Hessian factorizations per frame; the crowd runs {} "
        "with {} masses, its breakdown columns are per body and frame; crowd built in {:.1f} s)\n",
        model::to_string(integrators.front()), model::to_string(masses.front()), build_seconds);
    const nlohmann::json crowd_json = crowd > 0 ? nlohmann::json{{"bodies", crowd},
                                                                 {"threads", threads},
                                                                 {"fps", crowd_fps},
                                                                 {"ms_per_frame", ms(crowd_wall, frames)},
                                                                 {"elastic_ms_per_body", ms(total.elastic, n)},
                                                                 {"inertia_ms_per_body", ms(total.inertia, n)},
                                                                 {"solve_ms_per_body", ms(total.solve, n)},
                                                                 {"output_ms_per_body", ms(total.output, n)},
                                                                 {"build_seconds", build_seconds},
                                                                 {"paper_fps", 1.2}}
                                                : nlohmann::json(nullptr);
    write_json(out, {{"benchmark", "reduced"},
                     {"mesh", mesh},
                     {"point_handles", handles},
                     {"coordinates", coordinates},
                     {"cubature", cubature},
                     {"frames", frames},
                     {"one_body",
                      {{"threads", 1},
                       {"integrator", model::to_string(integrators.front())},
                       {"mass", model::to_string(masses.front())},
                       {"fps", one_fps},
                       {"ms_per_frame", ms(one_wall, frames)},
                       {"elastic_ms", ms(one.elastic, frames)},
                       {"inertia_ms", ms(one.inertia, frames)},
                       {"solve_ms", ms(one.solve, frames)},
                       {"output_ms", ms(one.output, frames)},
                       {"newton_per_frame", static_cast<double>(one.newton) / frames},
                       {"paper_fps", 30.0}}},
                     {"one_body_cases", combinations},
                     {"crowd", crowd_json}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_reduced: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
