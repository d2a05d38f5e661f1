// sflsh verify PROBLEM.toml --out DIR [--export-febio FILE.feb]: a canonical static or dynamic problem on a given
// gmsh mesh with a homogeneous material, for checking the full-space solver against other FEM codes, and the same
// problem as a FEBio 4 input.
#include "commands.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/work_limit.hpp>
#include <sflsh/fullspace/febio_export.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/fullspace/verify_problem.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/run/body_solver_factory.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace sflsh::app {

namespace {

struct VerifyOptions {
  std::string problem;
  std::string out;           ///< empty: no solve (only --export-febio)
  std::string export_febio;  ///< the FEBio 4 input to write, or empty
  bool no_vtk = false;
  bool allow_long = false;
  int threads = 0;  ///< assembly threads per process (0: the cores divided among the processes)
  fullspace::Preconditioner preconditioner = fullspace::Preconditioner::automatic;
};

/// Steps, recorded samples and their memory, before the solver is built.
WorkEstimate verify_work(const fullspace::VerifyProblem& spec, const model::Problem& problem) {
  WorkEstimate e;
  e.steps = spec.duration / spec.step;
  e.bodies = 1.0;
  const double samples = std::floor(e.steps / spec.record_every) + 1.0;
  e.body_frames = samples;
  // Every sample holds the whole mesh (3 doubles per node); every step a line of summary.json (~200 B).
  e.bytes = samples * 24.0 * problem.num_nodes() + 200.0 * e.steps;
  return e;
}

/// One recorded sample of the whole mesh.
struct Record {
  double t = 0.0;
  Eigen::VectorXd x;
};

void write_history(const std::filesystem::path& path, const model::Problem& problem, const std::vector<int>& nodes,
                   const std::vector<Record>& records) {
  std::ostringstream csv;
  csv << "t,node,ux,uy,uz\n";
  for (const Record& r : records) {
    for (int v : nodes) {
      csv << fmt::format("{:.12g},{},{:.12g},{:.12g},{:.12g}\n", r.t, v, r.x[3 * v] - problem.rest(v, 0),
                         r.x[3 * v + 1] - problem.rest(v, 1), r.x[3 * v + 2] - problem.rest(v, 2));
    }
  }
  write_text_atomically(path, csv.str());
}

/// What a verify run produced: the recorded samples, per-step records (stepping integrators) and the solver's
/// description for summary.json.
struct VerifyRun {
  std::vector<Record> records;
  nlohmann::json steps = nlohmann::json::array();
  nlohmann::json solver;
};

/// The whole number of steps of spec.step in spec.duration, within the work limits.
long step_count(const VerifyOptions& opt, const fullspace::VerifyProblem& spec, const model::Problem& problem) {
  check_work(verify_work(spec, problem), WorkLimits{}, opt.allow_long,
             fmt::format("{}: time.duration / time.step (and record.every)", opt.problem));
  require(spec.duration / spec.step < std::numeric_limits<int>::max(),
          "{}: time.step: {} s gives more than {} steps over time.duration = {} s", opt.problem, spec.step,
          std::numeric_limits<int>::max(), spec.duration);
  const auto steps = static_cast<long>(std::llround(spec.duration / spec.step));
  require(std::abs(static_cast<double>(steps) * spec.step - spec.duration) <= 1e-9 * std::max(1.0, spec.duration),
          "{}: time.duration = {} is not a whole number of steps of {}", opt.problem, spec.duration, spec.step);
  return steps;
}

/// The SUNDIALS reference (adaptive; one process), sampled every record.every steps.
VerifyRun run_reference(const fullspace::VerifyProblem& spec, const model::Problem& problem, long steps,
                        Progress& progress) {
  VerifyRun run;
  fullspace::ReferenceOptions ref;
  ref.rtol = spec.rtol;
  ref.atol = spec.atol;
  fullspace::ReferenceIntegrator integrator(problem, ref);
  const model::State state = model::initial_state(problem, 0.0);
  integrator.initialize(state);
  run.records.push_back({0.0, state.x});
  for (long k = spec.record_every; k <= steps; k += spec.record_every) {
    const model::State s = integrator.advance_to(static_cast<double>(k) * spec.step);
    run.records.push_back({s.t, s.x});
    progress.advance(static_cast<std::size_t>(spec.record_every));
  }
  const fullspace::ReferenceStats& st = integrator.stats();
  run.solver = {{"integrator", "reference"},
                {"rtol", spec.rtol},
                {"atol", spec.atol},
                {"steps", st.steps},
                {"rhs_evals", st.rhs_evals},
                {"jacobian_evals", st.jac_evals},
                {"nonlinear_iterations", st.nonlin_iters},
                {"error_test_failures", st.error_test_fails},
                {"mass_solves", st.mass_solves},
                {"seconds", st.seconds}};
  return run;
}

model::Integrator stepping_integrator(fullspace::VerifyProblem::Integrator integrator) {
  switch (integrator) {
    case fullspace::VerifyProblem::Integrator::bdf2:
      return model::Integrator::bdf2;
    case fullspace::VerifyProblem::Integrator::newmark:
      return model::Integrator::newmark;
    default:
      return model::Integrator::backward_euler;
  }
}

/// The full-space solver with the problem's integrator (quasi-static without density), one record per step.
VerifyRun run_stepping(const VerifyOptions& opt, const fullspace::VerifyProblem& spec, const model::Problem& problem,
                       long steps, const std::string& integrator_name, int size, Progress& progress) {
  VerifyRun run;
  const bool dynamic = problem.dynamic();
  run::SolverChoice choice;
  choice.quasi_static = !dynamic;
  choice.integrator = stepping_integrator(spec.integrator);
  choice.full.threads = opt.threads;
  choice.full.preconditioner = opt.preconditioner;
  model::State state = model::initial_state(problem, 0.0);
  if (!dynamic) {
    state.w.setZero();  // a static problem starts at equilibrium with the drives at t = 0
  } else if (choice.integrator == model::Integrator::newmark) {
    state.a = model::initial_acceleration(problem, state);  // p̈(0) from the equations of motion
  }
  const run::BuiltSolver built = run::make_body_solver(problem, choice, state);
  fullspace::FullSpaceSolver& integrator = *built.full;
  // Steps of the problem's own length, not frames of a motion: the frame loop with a fixed step, one step a frame.
  run.records.push_back({0.0, state.x});
  long newton = 0, linear = 0, builds = 0;
  model::FrameLoopOptions loop;
  loop.frames = static_cast<int>(steps) + 1;
  loop.step = spec.step;
  model::run_frames(integrator, loop, [&](int k, double, const model::StepStats& st) {
    newton += st.newton_iterations;
    linear += st.linear_iterations;
    builds += st.preconditioner_builds;
    run.steps.push_back({{"t", integrator.state().t},
                         {"newton_iterations", st.newton_iterations},
                         {"linear_iterations", st.linear_iterations},
                         {"substeps", st.substeps},
                         {"seconds", st.seconds}});
    if (k % spec.record_every == 0) run.records.push_back({integrator.state().t, integrator.state().x});
    progress.advance();
  });
  run.solver = {{"integrator", integrator_name},
                {"processes", size},
                {"threads_per_process", integrator.assembly_threads()},
                {"preconditioner", integrator.preconditioner_type()},
                {"newton_iterations", newton},
                {"linear_iterations", linear},
                {"preconditioner_builds", builds}};
  return run;
}

/// The samples as solution.pvd of .vtu frames (displacement [m] per node).
void write_solution_series(RunFolder& run, const model::Problem& problem, const std::vector<Record>& records) {
  vtk::PvdSeries series(run.stage("solution.pvd"));
  const vtk::Cells cells = problem.tets;
  for (std::size_t k = 0; k < records.size(); ++k) {
    const Record& r = records[k];
    const Eigen::Map<const vtk::Points> x(r.x.data(), problem.num_nodes(), 3);
    vtk::Fields fields;
    fields.point_data.push_back({"displacement", Eigen::MatrixXd(x - problem.rest), false});
    fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, r.t), false});
    const std::string name = fmt::format("solution_{:06d}.vtu", k);
    vtk::write_unstructured(run.stage(name), x, cells, fields);
    series.add(r.t, name);
  }
  series.write();
}

void run_verify(const VerifyOptions& opt, const Invocation& invocation, int rank, int size) {
  const auto t_start = std::chrono::steady_clock::now();
  const fullspace::VerifyProblem spec = fullspace::load_verify_problem(opt.problem);
  if (!opt.export_febio.empty() && rank == 0) fullspace::write_febio_input(spec, opt.export_febio);
  if (opt.out.empty()) return;
  model::Problem problem = fullspace::make_problem(spec);
  problem.validate();
  const std::vector<int> record_nodes = fullspace::record_nodes(spec);
  const bool reference = spec.integrator == fullspace::VerifyProblem::Integrator::reference;
  const bool dynamic = problem.dynamic();
  require(!reference || dynamic, "{}: integrator \"reference\" needs a dynamic problem (density > 0)", opt.problem);
  require(!reference || size == 1, "{}: the SUNDIALS reference integrator runs on one process (got {})", opt.problem,
          size);
  const long steps = step_count(opt, spec, problem);
  // What ran: the integrator of the problem file, or "static" without density (mass then means nothing).
  const std::string integrator_name = dynamic ? std::string(fullspace::to_string(spec.integrator)) : "static";
  const std::string mass_name = dynamic ? std::string(model::to_string(problem.mass_kind)) : "none";
  logger()->info(
      "verify {}: {} nodes, {} tets, {} {} steps of {:.6g} s ({} mass), recording {} nodes of '{}' every {} steps",
      spec.file.filename().string(), problem.num_nodes(), problem.num_tets(), steps,
      reference ? "reference (SUNDIALS)" : integrator_name, spec.step, mass_name, record_nodes.size(),
      spec.record_group, spec.record_every);

  Progress progress("time steps", static_cast<std::size_t>(steps), rank == 0);
  const VerifyRun result = reference ? run_reference(spec, problem, steps, progress)
                                     : run_stepping(opt, spec, problem, steps, integrator_name, size, progress);
  progress.finish();
  if (rank != 0) return;

  RunFolder run(opt.out);
  write_history(run.stage("history.csv"), problem, record_nodes, result.records);
  if (!opt.no_vtk) write_solution_series(run, problem, result.records);
  nlohmann::json summary = summary_header("verify", invocation.argc, invocation.argv);
  summary["problem"] = std::filesystem::absolute(spec.file).string();
  summary["mesh"] = {{"file", spec.mesh_path.string()},
                     {"nodes", problem.num_nodes()},
                     {"tets", problem.num_tets()},
                     {"flipped_tets", spec.mesh.flipped_tets}};
  summary["record"] = {{"group", spec.record_group},
                       {"nodes", record_nodes.size()},
                       {"every", spec.record_every},
                       {"samples", result.records.size()}};
  summary["integrator"] = integrator_name;
  summary["mass"] = mass_name;
  summary["solver"] = result.solver;
  summary["steps"] = result.steps;
  write_summary(run, summary, seconds_since(t_start), {.seconds = true});
  run.commit();
  logger()->info("wrote {} samples of {} nodes to {}/history.csv", result.records.size(), record_nodes.size(), opt.out);
}

}  // namespace

void register_verify_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<VerifyOptions>();
  auto* cmd = app.add_subcommand(
      "verify",
      "Solve a canonical problem (gmsh .msh mesh, homogeneous material, TOML description) and write the "
      "displacement history of a node group, for comparison with other FEM codes. PETSc options "
      "(-snes_*, -ksp_*, -pc_*) may follow; run in parallel with mpirun -n P.");
  cmd->add_option("problem", opt->problem, "Problem description (.toml)")->required();
  cmd->add_option("--out", opt->out,
                  "Output folder (history.csv, summary.json, solution.pvd); required unless --export-febio is given");
  cmd->add_option("--export-febio", opt->export_febio,
                  "Also write the problem as a FEBio 4 input (.feb, docs/fullspace.md); without --out, only that");
  cmd->add_flag("--no-vtk", opt->no_vtk, "Skip the .vtu series of the whole mesh");
  cmd->add_option("--threads", opt->threads,
                  "Assembly threads per process (0: the cores divided among the processes; PETSc's solves use one)")
      ->check(CLI::Range(0, 1024));
  const std::map<std::string, fullspace::Preconditioner> preconditioners = {
      {"automatic", fullspace::Preconditioner::automatic},
      {"direct", fullspace::Preconditioner::direct},
      {"icc", fullspace::Preconditioner::icc},
      {"gamg", fullspace::Preconditioner::gamg},
      {"hypre", fullspace::Preconditioner::hypre}};
  cmd->add_option("--preconditioner", opt->preconditioner,
                  "CG preconditioner of the Newton systems (docs/fullspace.md): automatic, direct, icc (block-Jacobi "
                  "ICC(0) in parallel), gamg or hypre; -pc_type overrides it")
      ->transform(CLI::CheckedTransformer(preconditioners));
  cmd->add_flag(
      "--allow-long", opt->allow_long,
      "Run even when the work estimate (steps, recorded samples, memory) exceeds the limits of docs/fullspace.md");
  cmd->callback([opt, invocation] {
    if (opt->out.empty() && opt->export_febio.empty()) throw CLI::RequiredError("--out DIR or --export-febio FILE.feb");
    with_petsc(invocation, [&](int rank, int size) { run_verify(*opt, invocation, rank, size); });
  });
}

}  // namespace sflsh::app
