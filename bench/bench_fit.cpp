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
#include <cstring>
#include <iostream>

namespace {
using namespace sflsh;
using Clock = std::chrono::steady_clock;
}  // namespace

int main(int argc, char** argv) {
  int subjects = 5, controls = 84, frames = 60, handles = 86, threads = 0, fd_columns = 6, iterations = 8;
  double fit_lambda = 0.0;
  std::string out = "bench_fit.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--subjects")
      subjects = std::stoi(argv[i + 1]);
    else if (a == "--controls")
      controls = std::stoi(argv[i + 1]);
    else if (a == "--frames")
      frames = std::stoi(argv[i + 1]);
    else if (a == "--handles")
      handles = std::stoi(argv[i + 1]);
    else if (a == "--threads")
      threads = std::stoi(argv[i + 1]);
    else if (a == "--fd-columns")
      fd_columns = std::stoi(argv[i + 1]);
    else if (a == "--iterations")
      iterations = std::stoi(argv[i + 1]);
    else if (a == "--fit")
      fit_lambda = std::stod(argv[i + 1]);
    else if (a == "--out")
      out = argv[i + 1];
    else {
      std::cerr << "bench_fit: unknown option " << a << "\n";
      return 2;
    }
  }
  try {
    const fullspace::PetscSession petsc;  // the fit's trust region is PETSc TAO
    const auto t_setup = Clock::now();
    const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
    const std::vector<body::Subject> all = body::default_subjects();
    std::vector<body::Betas> betas;
    for (int s = 1; s <= subjects; ++s)
      betas.push_back(body::find_subject(all, fmt::format("OPEN_TRAIN_{}", (s - 1) % 5 + 1)).beta);
    model::BodyLayerOptions lo;
    lo.size = meshing::SizePreset::coarse;
    std::vector<std::unique_ptr<reduced::DynamicsCase>> cases;
    for (int s = 0; s < subjects; ++s)
      for (const std::string m : {"one_leg_jump", "running_on_spot", "shake_hips"})
        cases.push_back(std::make_unique<reduced::DynamicsCase>(model, fmt::format("S{}", s),
                                                                betas[static_cast<std::size_t>(s)],
                                                                body::make_procedural_motion(m, 60.0, frames), lo));
    reduced::ParameterizationCache parameterizations(cases.front()->layer());
    reduced::ReducedModelOptions ro;
    ro.point_handles = handles;
    const reduced::ReducedModel rm = reduced::build_reduced_model(cases.front()->layer(), ro);
    reduced::SimulationPool pool(threads, MPI_COMM_NULL);
    reduced::FitContext context;
    context.body = &model;
    context.model = &rm;
    context.pool = &pool;
    context.bounds.thickness.max = 0.6;
    context.parameterization = [&](int n) -> const reduced::LayerParameterization& { return parameterizations.get(n); };
    context.progress = false;
    const reduced::LayerParameterization& param = parameterizations.get(controls);
    const double setup_seconds = sflsh::seconds_since(t_setup);

    // Targets: the dynamics of a perturbed uniform material (values do not matter for timing).
    material::KappaMatrix start(controls, 3);
    for (int i = 0; i < controls; ++i) start.row(i) << 0.4, 6000.0, 2500.0;
    std::vector<reduced::FitTarget> targets;
    std::vector<reduced::SimulationJob> jobs;
    for (std::size_t c = 0; c < cases.size(); ++c) jobs.push_back({static_cast<int>(c), start});
    std::vector<const reduced::DynamicsCase*> case_list;
    for (const auto& c : cases) case_list.push_back(c.get());
    auto t = Clock::now();
    const std::vector<Eigen::VectorXd> sigma = pool.run(case_list, jobs, param, rm, context.reduced);
    const double residual_seconds = sflsh::seconds_since(t);
    for (std::size_t c = 0; c < cases.size(); ++c)
      targets.push_back({cases[c].get(), static_cast<int>(c / 3), 1.1 * sigma[c]});

    // Set-up of one simulation (problem for κ, integrator, initial state) against the whole, one thread, every
    // case once after the residual above warmed the per-case caches; medians.
    std::vector<double> setup_times, simulation_times;
    for (const auto& c : cases) {
      const reduced::CaseDynamics d = c->simulate(param, start, rm, context.reduced);
      setup_times.push_back(d.setup_seconds);
      simulation_times.push_back(d.seconds);
    }
    auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    const double setup_median = median(setup_times), simulation_median = median(simulation_times);

    // Finite-difference columns: fd_columns × every case.
    std::vector<reduced::SimulationJob> fd_jobs;
    for (int k = 0; k < fd_columns; ++k) {
      material::KappaMatrix q = start;
      q(k % controls, k % 3) *= 1.002;
      for (std::size_t c = 0; c < cases.size(); ++c) fd_jobs.push_back({static_cast<int>(c), q});
    }
    t = Clock::now();
    pool.run(case_list, fd_jobs, param, rm, context.reduced);
    const double column_seconds = sflsh::seconds_since(t) / fd_columns;

    // Sensitivity runs: one per case.
    const Eigen::MatrixXd W = reduced::young_tet_map(param.retargeter(), param.phi(), rm.cubature.tets, 1.0);
    t = Clock::now();
    pool.run_tasks(
        static_cast<int>(cases.size()), [&](int) { return Eigen::Index{1}; },
        [&](int c) {
          Eigen::MatrixXd d;
          cases[static_cast<std::size_t>(c)]->simulate_with_sensitivity(param, start, rm, W, d, context.reduced);
          return Eigen::VectorXd::Constant(1, d.norm());
        });
    const double sensitivity_seconds = sflsh::seconds_since(t);
    // The same with the thickness columns too (exact through the retarget): the whole Jacobian.
    t = Clock::now();
    pool.run_tasks(
        static_cast<int>(cases.size()), [&](int) { return Eigen::Index{1}; },
        [&](int c) {
          Eigen::MatrixXd d;
          cases[static_cast<std::size_t>(c)]->simulate_with_sensitivity(param, start, rm, W, d, context.reduced, true);
          return Eigen::VectorXd::Constant(1, d.norm());
        });
    const double exact_seconds = sflsh::seconds_since(t);

    const double fd_jacobian = 3.0 * controls * column_seconds;
    const double hybrid_jacobian = controls * column_seconds + sensitivity_seconds;
    // Whole progressive fit: per stage `iterations` × (Jacobian + 2 residuals); the sensitivity part scales
    // with its 2N columns (the solve and the history products), bounded here by linear scaling.
    const double exact_jacobian = exact_seconds;
    double fit_fd = 0.0, fit_hybrid = 0.0, fit_exact = 0.0;
    for (int n : {1, 12, 24, 84}) {
      const double scale = static_cast<double>(n) / controls;
      fit_fd += iterations * (3.0 * n * column_seconds + 2.0 * residual_seconds);
      fit_hybrid +=
          iterations * (n * column_seconds + std::max(scale, 0.25) * sensitivity_seconds + 2.0 * residual_seconds);
      fit_exact += iterations * (std::max(scale, 0.25) * exact_seconds + 2.0 * residual_seconds);
    }
    std::cout << fmt::format(
        "bench_fit: {} subjects × 3 train motions = {} cases, N = {}, {} frames, {} handles ({} coordinates), "
        "{} cubature tets, {} threads; setup {:.1f} s\n\n",
        subjects, cases.size(), controls, frames, handles, rm.subspace.num_dofs(), rm.cubature.size(), pool.threads(),
        setup_seconds);
    std::cout << fmt::format("{:<58} {:>12}\n", "quantity", "seconds");
    auto row = [](const std::string& name, double s) { std::cout << fmt::format("{:<58} {:>12.2f}\n", name, s); };
    row(fmt::format("one residual ({} simulations)", cases.size()), residual_seconds);
    row("one simulation, one thread (median over the cases)", simulation_median);
    row("  of which set-up: problem for κ, integrator, initial state", setup_median);
    row(fmt::format("one finite-difference column ({} simulations)", cases.size()), column_seconds);
    row(fmt::format("Young columns by sensitivities ({} runs, {} columns each)", cases.size(), 2 * controls),
        sensitivity_seconds);
    row(fmt::format("Jacobian by finite differences ({} columns, projected)", 3 * controls), fd_jacobian);
    row(fmt::format("Jacobian by sensitivities + {} thickness columns (projected)", controls), hybrid_jacobian);
    row(fmt::format("Jacobian by sensitivities, thickness too ({} runs, {} columns each)", cases.size(), 3 * controls),
        exact_jacobian);
    row(fmt::format("whole fit N = 1/12/24/84 × {} iterations, finite differences (projected)", iterations), fit_fd);
    row(fmt::format("whole fit N = 1/12/24/84 × {} iterations, sensitivities + thickness differences (projected)",
                    iterations),
        fit_hybrid);
    row(fmt::format("whole fit N = 1/12/24/84 × {} iterations, sensitivities with thickness (projected)", iterations),
        fit_exact);
    nlohmann::json fits = nlohmann::json::array();
    if (fit_lambda > 0.0) {
      // Targets: each subject's dynamics under a field that varies over the control points and with β.
      std::vector<reduced::FitTarget> fit_targets;
      std::vector<reduced::SimulationJob> truth_jobs;
      for (std::size_t c = 0; c < cases.size(); ++c) {
        const double s = static_cast<double>(c / 3) / std::max(1, subjects - 1);
        material::KappaMatrix k(controls, 3);
        for (int i = 0; i < controls; ++i)
          k.row(i) << 0.25 + 0.25 * (0.5 + 0.5 * std::sin(1.3 * i + s)),
              4000.0 + 6000.0 * ((i * 7) % 11) / 10.0 * (1.0 - 0.3 * s), 2000.0 + 2000.0 * ((i * 5) % 7) / 6.0;
        truth_jobs.push_back({static_cast<int>(c), k});
      }
      const std::vector<Eigen::VectorXd> truth = pool.run(case_list, truth_jobs, param, rm, context.reduced);
      for (std::size_t c = 0; c < cases.size(); ++c)
        fit_targets.push_back({cases[c].get(), static_cast<int>(c / 3), truth[c]});
      reduced::FitSpec spec;
      spec.kind = reduced::FitKind::shape;
      spec.regularizer = reduced::Regularizer::local;
      spec.betas = betas;
      spec.iterations = iterations;
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
        const long before = pool.simulations();
        const auto t0 = Clock::now();
        reduced::FitResult r = reduced::fit_elasticity(context, fit_targets, spec);
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
                        {"simulations", pool.simulations() - before},
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
    }
    write_json(out, {{"benchmark", "fit"},
                     {"fits", fits},
                     {"subjects", subjects},
                     {"cases", cases.size()},
                     {"controls", controls},
                     {"frames", frames},
                     {"point_handles", handles},
                     {"threads", pool.threads()},
                     {"residual_seconds", residual_seconds},
                     {"fd_column_seconds", column_seconds},
                     {"simulation_seconds_median", simulation_median},
                     {"simulation_setup_seconds_median", setup_median},
                     {"sensitivity_seconds", sensitivity_seconds},
                     {"jacobian_fd_seconds_projected", fd_jacobian},
                     {"jacobian_sensitivity_seconds_projected", hybrid_jacobian},
                     {"whole_fit_fd_seconds_projected", fit_fd},
                     {"whole_fit_sensitivity_seconds_projected", fit_hybrid},
                     {"jacobian_exact_seconds", exact_jacobian},
                     {"whole_fit_exact_seconds_projected", fit_exact},
                     {"iterations_per_stage", iterations}});
    std::cout << "\nwrote " << out << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "bench_fit: " << e.what() << "\n";
    return 1;
  }
}
