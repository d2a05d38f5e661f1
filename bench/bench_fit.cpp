// bench_fit: what one trust-region iteration of the fit (SFLSH §5) costs, and the projected time of a whole
// progressive fit. For M subjects × the train motions on the coarse layer, measures
//   - one residual (M·motions simulations),
//   - the Young-modulus columns of dσ/dq by forward sensitivities (one differentiated run per case),
//   - the cost of one finite-difference column (M·motions simulations, timed on --fd-columns columns),
// and one whole Jacobian by sensitivities with the thickness columns (one differentiated run per case), and
// projects one Jacobian by finite differences (3N columns, the paper) and by sensitivities + thickness
// differences (N columns), and the whole fit N = 1 → 12 → 24 → 84 with --iterations per stage, each
// iteration one Jacobian and two residuals (TAO's trial and the accepted point).
// With --fit λ it also runs whole shape fits (local regularizer) on these cases, the way a leave-one-out fold of
// `sflsh validate` does: cold through the stages 1, 12, 24, … ≤ N at λ, then warm-started at λ/10 at the last
// stage only (the λ sweep's continuation), against targets made by a heterogeneous shape-dependent field.
//   bench_fit [--subjects 5] [--controls 84] [--frames 60] [--handles 86] [--threads 0] [--fd-columns 6]
//             [--iterations 8] [--fit λ] [--out bench_fit.json]
#include "bench_options.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/petsc_session.hpp>
#include <sflsh/reduced/elasticity_fit.hpp>
#include <sflsh/reduced/young_map.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>

namespace {

using namespace sflsh;
using Clock = std::chrono::steady_clock;

struct FitOptions {
  int subjects = 5, controls = 84, frames = 60, handles = 86, threads = 0, fd_columns = 6, iterations = 8;
  double fit_lambda = 0.0;
  std::string out = "bench_fit.json";
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, FitOptions& o) {
  CLI::App app{
      "What one trust-region iteration of the fit (SFLSH §5) costs, and the projected time of a whole "
      "progressive fit, for M subjects × the train motions on the coarse layer.",
      "bench_fit"};
  bench::use_bench_defaults(app);
  app.add_option("--subjects", o.subjects, "Subjects M (OPEN_TRAIN_1…5, repeated beyond 5), 3 train motions each");
  app.add_option("--controls", o.controls, "Material control points N");
  app.add_option("--frames", o.frames, "Frames of each motion (60 fps)");
  app.add_option("--handles", o.handles, "Point handles of the reduced model");
  app.add_option("--threads", o.threads, "Threads of the simulation pool (0: all hardware threads)");
  app.add_option("--fd-columns", o.fd_columns, "Finite-difference columns timed (each M × 3 simulations)");
  app.add_option("--iterations", o.iterations, "Trust-region iterations per stage of the projected (and run) fits");
  app.add_option("--fit", o.fit_lambda,
                 "Also run whole shape fits (local regularizer) at this λ, cold, then warm-started at λ/10 "
                 "(0: none)");
  app.add_option("--out", o.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

/// What the measurements share: the cases, the reduced model, the pool and the fit context over them.
struct Bench {
  const FitOptions& o;
  const std::vector<std::unique_ptr<reduced::DynamicsCase>>& cases;
  std::vector<const reduced::DynamicsCase*> case_list;
  const reduced::ReducedModel& rm;
  reduced::SimulationPool& pool;
  reduced::FitContext& context;
  const reduced::LayerParameterization& param;
};

/// Measured costs [s].
struct Costs {
  double residual = 0.0;           ///< one residual (every case)
  double simulation_median = 0.0;  ///< one simulation on one thread
  double setup_median = 0.0;       ///< of which its set-up
  double column = 0.0;             ///< one finite-difference column (every case)
  double sensitivity = 0.0;        ///< the Young columns by sensitivities (every case)
  double exact = 0.0;              ///< every column by sensitivities, thickness too (every case)
};

/// One differentiated run per case [s]; `thickness`: with the thickness columns (exact through the retarget).
double time_sensitivity_runs(const Bench& b, const material::KappaMatrix& start, const Eigen::MatrixXd& W,
                             bool thickness) {
  const auto t = Clock::now();
  b.pool.run_tasks(
      static_cast<int>(b.cases.size()), [&](int) { return Eigen::Index{1}; },
      [&](int c) {
        Eigen::MatrixXd d;
        b.cases[static_cast<std::size_t>(c)]->simulate_with_sensitivity(b.param, start, b.rm, W, d, b.context.reduced,
                                                                        thickness);
        return Eigen::VectorXd::Constant(1, d.norm());
      });
  return sflsh::seconds_since(t);
}

Costs measure_costs(const Bench& b) {
  const int controls = b.o.controls, fd_columns = b.o.fd_columns;
  const auto& cases = b.cases;
  Costs costs;
  // Targets: the dynamics of a perturbed uniform material (values do not matter for timing).
  material::KappaMatrix start(controls, 3);
  for (int i = 0; i < controls; ++i) start.row(i) << 0.4, 6000.0, 2500.0;
  std::vector<reduced::FitTarget> targets;
  std::vector<reduced::SimulationJob> jobs;
  for (std::size_t c = 0; c < cases.size(); ++c) jobs.push_back({static_cast<int>(c), start});
  auto t = Clock::now();
  const std::vector<Eigen::VectorXd> sigma = b.pool.run(b.case_list, jobs, b.param, b.rm, b.context.reduced);
  costs.residual = sflsh::seconds_since(t);
  for (std::size_t c = 0; c < cases.size(); ++c)
    targets.push_back({cases[c].get(), static_cast<int>(c / 3), 1.1 * sigma[c]});

  // Set-up of one simulation (problem for κ, integrator, initial state) against the whole, one thread, every
  // case once after the residual above warmed the per-case caches; medians.
  std::vector<double> setup_times, simulation_times;
  for (const auto& c : cases) {
    const reduced::CaseDynamics d = c->simulate(b.param, start, b.rm, b.context.reduced);
    setup_times.push_back(d.setup_seconds);
    simulation_times.push_back(d.seconds);
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  costs.setup_median = median(setup_times);
  costs.simulation_median = median(simulation_times);

  // Finite-difference columns: fd_columns × every case.
  std::vector<reduced::SimulationJob> fd_jobs;
  for (int k = 0; k < fd_columns; ++k) {
    material::KappaMatrix q = start;
    q(k % controls, k % 3) *= 1.002;
    for (std::size_t c = 0; c < cases.size(); ++c) fd_jobs.push_back({static_cast<int>(c), q});
  }
  t = Clock::now();
  b.pool.run(b.case_list, fd_jobs, b.param, b.rm, b.context.reduced);
  costs.column = sflsh::seconds_since(t) / fd_columns;

  // Sensitivity runs: one per case; then the same with the thickness columns too: the whole Jacobian.
  const Eigen::MatrixXd W = reduced::young_tet_map(b.param.retargeter(), b.param.phi(), b.rm.cubature.tets, 1.0);
  costs.sensitivity = time_sensitivity_runs(b, start, W, false);
  costs.exact = time_sensitivity_runs(b, start, W, true);
  return costs;
}

/// Projected costs [s]: one Jacobian and the whole fit by each method.
struct Projections {
  double fd_jacobian = 0.0, hybrid_jacobian = 0.0, exact_jacobian = 0.0;
  double fit_fd = 0.0, fit_hybrid = 0.0, fit_exact = 0.0;
};

Projections project(const Costs& c, int controls, int iterations) {
  Projections p;
  p.fd_jacobian = 3.0 * controls * c.column;
  p.hybrid_jacobian = controls * c.column + c.sensitivity;
  // Whole progressive fit: per stage `iterations` × (Jacobian + 2 residuals); the sensitivity part scales
  // with its 2N columns (the solve and the history products), bounded here by linear scaling.
  p.exact_jacobian = c.exact;
  for (int n : {1, 12, 24, 84}) {
    const double scale = static_cast<double>(n) / controls;
    p.fit_fd += iterations * (3.0 * n * c.column + 2.0 * c.residual);
    p.fit_hybrid += iterations * (n * c.column + std::max(scale, 0.25) * c.sensitivity + 2.0 * c.residual);
    p.fit_exact += iterations * (std::max(scale, 0.25) * c.exact + 2.0 * c.residual);
  }
  return p;
}

/// The table of measured and projected costs.
void print_costs(const Bench& b, const Costs& c, const Projections& p, double setup_seconds) {
  const int controls = b.o.controls, iterations = b.o.iterations;
  const std::size_t cases = b.cases.size();
  std::cout << fmt::format(
      "bench_fit: {} subjects × 3 train motions = {} cases, N = {}, {} frames, {} handles ({} coordinates), "
      "{} cubature tets, {} threads; setup {:.1f} s\n\n",
      b.o.subjects, cases, controls, b.o.frames, b.o.handles, b.rm.subspace.num_dofs(), b.rm.cubature.size(),
      b.pool.threads(), setup_seconds);
  std::cout << fmt::format("{:<58} {:>12}\n", "quantity", "seconds");
  auto row = [](const std::string& name, double s) { std::cout << fmt::format("{:<58} {:>12.2f}\n", name, s); };
  row(fmt::format("one residual ({} simulations)", cases), c.residual);
  row("one simulation, one thread (median over the cases)", c.simulation_median);
  row("  of which set-up: problem for κ, integrator, initial state", c.setup_median);
  row(fmt::format("one finite-difference column ({} simulations)", cases), c.column);
  row(fmt::format("Young columns by sensitivities ({} runs, {} columns each)", cases, 2 * controls), c.sensitivity);
  row(fmt::format("Jacobian by finite differences ({} columns, projected)", 3 * controls), p.fd_jacobian);
  row(fmt::format("Jacobian by sensitivities + {} thickness columns (projected)", controls), p.hybrid_jacobian);
  row(fmt::format("Jacobian by sensitivities, thickness too ({} runs, {} columns each)", cases, 3 * controls),
      p.exact_jacobian);
  row(fmt::format("whole fit N = 1/12/24/84 × {} iterations, finite differences (projected)", iterations), p.fit_fd);
  row(fmt::format("whole fit N = 1/12/24/84 × {} iterations, sensitivities + thickness differences (projected)",
                  iterations),
      p.fit_hybrid);
  row(fmt::format("whole fit N = 1/12/24/84 × {} iterations, sensitivities with thickness (projected)", iterations),
      p.fit_exact);
}

/// Targets of the whole fits: each subject's dynamics under a field that varies over the control points and with β.
std::vector<reduced::FitTarget> make_fit_targets(const Bench& b) {
  const int controls = b.o.controls, subjects = b.o.subjects;
  std::vector<reduced::FitTarget> fit_targets;
  std::vector<reduced::SimulationJob> truth_jobs;
  for (std::size_t c = 0; c < b.cases.size(); ++c) {
    const double s = static_cast<double>(c / 3) / std::max(1, subjects - 1);
    material::KappaMatrix k(controls, 3);
    for (int i = 0; i < controls; ++i)
      k.row(i) << 0.25 + 0.25 * (0.5 + 0.5 * std::sin(1.3 * i + s)),
          4000.0 + 6000.0 * ((i * 7) % 11) / 10.0 * (1.0 - 0.3 * s), 2000.0 + 2000.0 * ((i * 5) % 7) / 6.0;
    truth_jobs.push_back({static_cast<int>(c), k});
  }
  const std::vector<Eigen::VectorXd> truth = b.pool.run(b.case_list, truth_jobs, b.param, b.rm, b.context.reduced);
  for (std::size_t c = 0; c < b.cases.size(); ++c)
    fit_targets.push_back({b.cases[c].get(), static_cast<int>(c / 3), truth[c]});
  return fit_targets;
}

/// --fit λ: whole shape fits, cold through the stages at λ, then warm-started at λ/10 at the last stage; their table
/// (printed) and JSON.
nlohmann::json run_fits(const Bench& b, const std::vector<body::Betas>& betas) {
  const int controls = b.o.controls;
  const double fit_lambda = b.o.fit_lambda;
  nlohmann::json fits = nlohmann::json::array();
  const std::vector<reduced::FitTarget> fit_targets = make_fit_targets(b);
  reduced::FitSpec spec;
  spec.kind = reduced::FitKind::shape;
  spec.regularizer = reduced::Regularizer::local;
  spec.betas = betas;
  spec.iterations = b.o.iterations;
  spec.stages.clear();
  for (int n : {1, 12, 24, 84})
    if (n < controls) spec.stages.push_back(n);
  spec.stages.push_back(controls);
  auto run_fit = [&](const std::string& name, double lambda, const reduced::FitResult* from) {
    spec.name = name;
    spec.lambda = lambda;
    if (from) {
      spec.warm_start = from->p;
      spec.warm_start_from = from->name;
    }
    const long before = b.pool.simulations();
    const auto t0 = Clock::now();
    reduced::FitResult r = reduced::fit_elasticity(b.context, fit_targets, spec);
    const double seconds = sflsh::seconds_since(t0);
    int its = 0, jacobians = 0;
    for (const auto& st : r.stages) {
      its += st.iterations;
      jacobians += st.jacobians;
    }
    fits.push_back({{"fit", name},
                    {"lambda", lambda},
                    {"warm_start", from != nullptr},
                    {"seconds", seconds},
                    {"stages", r.stages.size()},
                    {"iterations", its},
                    {"jacobians", jacobians},
                    {"simulations", b.pool.simulations() - before},
                    {"loss_fit_mm2", r.stages.back().loss_fit}});
    return r;
  };
  const reduced::FitResult cold = run_fit("cold", fit_lambda, nullptr);
  run_fit("warm", 0.1 * fit_lambda, &cold);
  std::cout << fmt::format("\n{:<6} {:>8} {:>9} {:>7} {:>11} {:>10} {:>12} {:>12}\n", "fit", "lambda", "stages",
                           "iters", "jacobians", "sims", "loss [mm2]", "seconds");
  for (const auto& f : fits)
    std::cout << fmt::format("{:<6} {:>8g} {:>9} {:>7} {:>11} {:>10} {:>12.5g} {:>12.1f}\n",
                             f["fit"].get<std::string>(), f["lambda"].get<double>(), f["stages"].get<int>(),
                             f["iterations"].get<int>(), f["jacobians"].get<int>(), f["simulations"].get<long>(),
                             f["loss_fit_mm2"].get<double>(), f["seconds"].get<double>());
  return fits;
}

void write_results(const Bench& b, const nlohmann::json& fits, const Costs& c, const Projections& p) {
  write_json(b.o.out, {{"benchmark", "fit"},
                       {"fits", fits},
                       {"subjects", b.o.subjects},
                       {"cases", b.cases.size()},
                       {"controls", b.o.controls},
                       {"frames", b.o.frames},
                       {"point_handles", b.o.handles},
                       {"threads", b.pool.threads()},
                       {"residual_seconds", c.residual},
                       {"fd_column_seconds", c.column},
                       {"simulation_seconds_median", c.simulation_median},
                       {"simulation_setup_seconds_median", c.setup_median},
                       {"sensitivity_seconds", c.sensitivity},
                       {"jacobian_fd_seconds_projected", p.fd_jacobian},
                       {"jacobian_sensitivity_seconds_projected", p.hybrid_jacobian},
                       {"whole_fit_fd_seconds_projected", p.fit_fd},
                       {"whole_fit_sensitivity_seconds_projected", p.fit_hybrid},
                       {"jacobian_exact_seconds", p.exact_jacobian},
                       {"whole_fit_exact_seconds_projected", p.fit_exact},
                       {"iterations_per_stage", b.o.iterations}});
}

/// Set-up (the cases, the reduced model, the pool), the measured and projected costs, the fits, the JSON.
void run_benchmark(const FitOptions& o) {
  const fullspace::PetscSession petsc;  // the fit's trust region is PETSc TAO
  const auto t_setup = Clock::now();
  const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  const std::vector<body::Subject> all = body::default_subjects();
  std::vector<body::Betas> betas;
  for (int s = 1; s <= o.subjects; ++s)
    betas.push_back(body::find_subject(all, fmt::format("OPEN_TRAIN_{}", (s - 1) % 5 + 1)).beta);
  model::BodyLayerOptions lo;
  lo.size = meshing::SizePreset::coarse;
  std::vector<std::unique_ptr<reduced::DynamicsCase>> cases;
  for (int s = 0; s < o.subjects; ++s)
    for (const std::string m : {"one_leg_jump", "running_on_spot", "shake_hips"})
      cases.push_back(std::make_unique<reduced::DynamicsCase>(model, fmt::format("S{}", s),
                                                              betas[static_cast<std::size_t>(s)],
                                                              body::make_procedural_motion(m, 60.0, o.frames), lo));
  reduced::ParameterizationCache parameterizations(cases.front()->layer());
  reduced::ReducedModelOptions ro;
  ro.point_handles = o.handles;
  const reduced::ReducedModel rm = reduced::build_reduced_model(cases.front()->layer(), ro);
  reduced::SimulationPool pool(o.threads, MPI_COMM_NULL);
  reduced::FitContext context;
  context.body = &model;
  context.model = &rm;
  context.pool = &pool;
  context.bounds.thickness.max = 0.6;
  context.parameterization = [&](int n) -> const reduced::LayerParameterization& { return parameterizations.get(n); };
  context.progress = false;
  const reduced::LayerParameterization& param = parameterizations.get(o.controls);
  const double setup_seconds = sflsh::seconds_since(t_setup);

  Bench b{o, cases, {}, rm, pool, context, param};
  for (const auto& c : cases) b.case_list.push_back(c.get());
  const Costs costs = measure_costs(b);
  const Projections projections = project(costs, o.controls, o.iterations);
  print_costs(b, costs, projections, setup_seconds);
  const nlohmann::json fits = o.fit_lambda > 0.0 ? run_fits(b, betas) : nlohmann::json::array();
  write_results(b, fits, costs, projections);
  std::cout << "\nwrote " << o.out << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  FitOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  try {
    run_benchmark(o);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "bench_fit: " << e.what() << "\n";
    return 1;
  }
}
