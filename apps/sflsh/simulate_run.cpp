#include "simulate_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sflsh/body/motion.hpp>
#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/work_limit.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

namespace sflsh::app {

void add_reduced_run_options(CLI::App& cmd, BodyRunSettings& s) {
  cmd.add_option("--handles", s.handles, "Reduced: point handles inside the layer (plus the 24 bone handles)");
  cmd.add_option("--cubature", s.cubature,
                 "Reduced: cubature tets K (default −1 = auto: from max(200, 0.8 × coordinates), grown until the cubature sees "
                 "every direction of the subspace with ≥ 1/4 of its exact rest stiffness; 0 = every tet, exact)");
  cmd.add_option("--cubature-weights", s.cubature_weights, "Reduced: nnls (training-free force matching) | voronoi")
      ->check(CLI::IsMember({"nnls", "voronoi"}));
  cmd.add_flag("--affine", s.affine, "Reduced: affine point handles (12 coordinates each instead of 3)");
  cmd.add_option("--newton-tolerance", s.newton_tolerance,
                 "Reduced: stop Newton when the estimated distance of every handle to the step's solution is below this [m]");
}

void add_integrator_option(CLI::App& cmd, std::string& integrator) {
  cmd.add_option("--integrator", integrator,
                 "Time integrator: backward_euler (default; first order, damps) | bdf2 (second order, mild damping) | "
                 "newmark (trapezoidal, no numerical damping); docs/integrators.md");
}

namespace {

/// One body's steps (frames × substeps), frames and per-frame records (motion sample, summary entry: ~1 kB).
void check_body_run_work(const BodyRunSettings& opt, double frames) {
  WorkEstimate e;
  e.bodies = 1.0;
  e.body_frames = frames;
  e.steps = std::max(0.0, frames - 1.0) * opt.substeps;
  e.bytes = 1024.0 * frames;
  check_work(e, WorkLimits{}, opt.allow_long, "--frames × --substeps (or the motion's length)");
}

}  // namespace

nlohmann::json run_body_simulation(const BodyRunSettings& opt, RunFolder* frames_to, int rank, int size,
                                   const BodyRunReporting& reporting) {
  const auto t_start = Clock::now();
  require(opt.solver == "full" || opt.solver == "reduced", "--solver {}: expected full or reduced", opt.solver);
  require(opt.handles >= 1, "--handles must be at least 1, got {}", opt.handles);
  require(opt.cubature >= -1, "--cubature must be −1 (auto), 0 (every tet) or a tet count, got {}", opt.cubature);
  require(opt.fps > 0.0, "--fps must be positive, got {}", opt.fps);
  require(opt.substeps >= 1, "--substeps must be at least 1, got {}", opt.substeps);
  require(opt.frames >= 0, "--frames must be non-negative, got {}", opt.frames);
  check_layer_settings(opt.layer);
  const model::Integrator integrator = model::parse_integrator(opt.integrator, "--integrator");

  const body::BodyModel model = load_selected_body(opt.subject);
  std::string subject_label;
  const body::Betas beta = selected_betas(opt.subject, subject_label, "simulate");
  // Before the motion is sampled (frames × 600 B) or anything is built: --frames and --substeps as given …
  check_body_run_work(opt, opt.frames);
  const body::Motion motion = body::load_motion(opt.motion, opt.fps, opt.frames);
  motion.validate();
  check_body_run_work(opt, static_cast<double>(motion.num_frames()));   // … and with the motion's own length

  const std::optional<material::MaterialFile> material_file = load_layer_material(opt.layer);
  const model::BodyLayerOptions layer_options = body_layer_options(opt.layer, opt.mesh);
  const auto t_build = Clock::now();
  model::BodyLayer layer = model::build_body_layer(model, beta, motion, material_file ? &*material_file : nullptr,
                                                   opt.layer.control_points, layer_options);
  const double build_seconds = seconds_since(t_build);
  const model::Problem& problem = layer.problem;
  logger()->log(
      reporting.log_details ? spdlog::level::info : spdlog::level::debug,
      "simulate: {} nodes ({} free), {} tets, {} frames at {} fps, {} substep(s), {} + {} mass, {} process(es)",
      problem.num_nodes(), problem.num_nodes() - static_cast<int>(problem.dirichlet.dof.size() / 3), problem.num_tets(),
      motion.num_frames(), motion.fps, opt.substeps, model::to_string(integrator), model::to_string(problem.mass_kind),
      size);

  const bool use_reduced = opt.solver == "reduced";
  require(!use_reduced || size == 1, "--solver reduced runs on one process (got {}); parallelize over bodies instead",
          size);
  std::optional<reduced::ReducedModel> reduced_model;
  std::unique_ptr<fullspace::FullSpaceSolver> full;
  std::unique_ptr<reduced::ReducedSolver> fast;
  const auto t_model = Clock::now();
  if (use_reduced) {
    ReducedSettings reduced_settings;
    reduced_settings.cubature_weights = opt.cubature_weights;
    reduced_settings.affine = opt.affine;
    reduced_model = reduced::build_reduced_model(
        layer, reduced_model_options(reduced_settings, opt.handles, opt.cubature, opt.layer.cache));
    reduced::ReducedOptions solver_options;
    solver_options.integrator = integrator;
    require(opt.newton_tolerance > 0.0 && std::isfinite(opt.newton_tolerance), "--newton-tolerance must be a positive length in metres, got {}",
            opt.newton_tolerance);
    solver_options.step_tolerance = opt.newton_tolerance;
    fast = std::make_unique<reduced::ReducedSolver>(problem, reduced_model->subspace, reduced_model->cubature,
                                                    solver_options);
    fast->initialize(model::initial_state(problem, 0.0));
  } else {
    fullspace::FullSpaceOptions solver_options;
    solver_options.integrator = integrator;
    full = std::make_unique<fullspace::FullSpaceSolver>(problem, MPI_COMM_WORLD, solver_options);
    full->initialize(model::initial_state(problem, 0.0));
  }
  const double model_seconds = seconds_since(t_model);
  if (reporting.on_setup)
    reporting.on_setup({{"tets", problem.num_tets()},
                        {"coordinates", reduced_model ? reduced_model->subspace.num_dofs() : 0},
                        {"cubature", reduced_model ? reduced_model->cubature.size() : 0}});
  model::BodySolver& solver = use_reduced ? static_cast<model::BodySolver&>(*fast) : *full;

  // Declared after the run folder (the caller's): a failing run drops its pending writes before the folder is removed.
  std::optional<BackgroundJobs> jobs;
  const bool write = rank == 0 && frames_to != nullptr;
  if (write) jobs.emplace(8);
  model::SimulationWriterOptions writer_options;
  writer_options.write_layer = opt.write_layer;
  writer_options.jobs = jobs ? &*jobs : nullptr;
  writer_options.format = opt.format;
  writer_options.precision = xdmf::parse_precision(opt.precision, "--precision");
  model::SimulationWriter writer(layer, write ? frames_to : nullptr, writer_options);
  const int num_frames = static_cast<int>(motion.num_frames());
  writer.add_frame(0, 0.0, solver.current_state(), true);

  nlohmann::json frames = nlohmann::json::array();
  frames.push_back({{"frame", 0}, {"t", 0.0}, {"newton_iterations", 0}, {"linear_iterations", 0}, {"seconds", 0.0}});
  const double h = 1.0 / (motion.fps * opt.substeps);
  Progress progress("frames", motion.num_frames() > 0 ? motion.num_frames() - 1 : 0, rank == 0 && reporting.progress);
  double output_seconds = 0.0;
  model::FrameLoopOptions loop;
  loop.frames = static_cast<int>(motion.num_frames());
  loop.fps = motion.fps;
  loop.substeps = opt.substeps;
  const model::StepStats total = model::run_frames(solver, loop, [&](int frame, double, const model::StepStats& st) {
    const auto f = static_cast<std::size_t>(frame);
    const auto t_output = Clock::now();
    const model::State state = solver.current_state();
    const model::Energies e = model::energies(problem, state);
    writer.add_frame(frame, motion.time(f), state, model::is_written_frame(frame, num_frames, opt.every));
    output_seconds += seconds_since(t_output);
    frames.push_back({{"frame", f},
                      {"t", motion.time(f)},
                      {"newton_iterations", st.newton_iterations},
                      {"linear_iterations", st.linear_iterations},
                      {"failed_attempts", st.failed_attempts},
                      {"seconds", st.seconds},
                      {"energy", {{"kinetic", e.kinetic}, {"elastic", e.elastic}, {"gravity", e.gravity}}}});
    progress.advance();
    if (reporting.on_frame) reporting.on_frame(frame);
  });
  progress.finish();
  const double solve_seconds = total.seconds;
  if (rank != 0) return {};

  const auto t_drain = Clock::now();
  if (jobs) jobs->wait();
  output_seconds += seconds_since(t_drain);
  writer.finish();
  nlohmann::json summary = nlohmann::json::object();
  summary["compression"] = vtk::to_string(writer_options.compression);
  summary["integrator"] = model::to_string(integrator);
  summary["mass"] = model::to_string(problem.mass_kind);
  summary["solver"] = {{"name", opt.solver},
                       {"integrator", model::to_string(integrator)},
                       {"startup_steps", total.startup_steps},
                       {"processes", size},
                       {"step", h},
                       {"substeps", opt.substeps},
                       {"newton_iterations", total.newton_iterations},
                       {"linear_iterations", total.linear_iterations},
                       {"failed_attempts", total.failed_attempts},
                       {"projected_retries", total.projected_retries},
                       {"truncated_solves", total.truncated_solves}};
  summary["body"] = opt.subject.body_path.empty() ? "open_body" : opt.subject.body_path;
  summary["subject"] = subject_label;
  summary["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  summary["motion"] = {
      {"name", motion.name}, {"source", motion.source}, {"fps", motion.fps}, {"frames", motion.num_frames()}};
  summary["mesh"] = {{"mesher", opt.layer.mesher},
                     {"size", opt.mesh},
                     {"nodes", problem.num_nodes()},
                     {"tets", problem.num_tets()},
                     {"constrained_dofs", problem.dirichlet.dof.size()}};
  summary["material"] = material_summary(opt.layer, material_file);
  if (reduced_model) {
    summary["reduced"] = {{"point_handles", reduced_model->handles.point_nodes.size()},
                          {"bone_handles", reduced_model->handles.bone_joints().size()},
                          {"affine", opt.affine},
                          {"coordinates", reduced_model->subspace.num_dofs()},
                          {"basis_nonzeros", reduced_model->subspace.basis.nonZeros()},
                          {"cubature", fast->cubature().size()},
                          {"cubature_model", reduced_model->cubature.size()},
                          {"cubature_added", fast->cubature_added()},
                          {"cubature_method", reduced_model->cubature.method},
                          {"stiffness_ratio_max", reduced_model->cubature.stiffness_ratio_max},
                          {"stiffness_ratio_min", reduced_model->cubature.stiffness_ratio_min},
                          {"guard", fast->guard() ? nlohmann::json{{"exponent_limit", fast->guard()->exponent_limit()},
                                                                   {"guarded_tets", fast->guard()->num_guarded()},
                                                                   {"checks", fast->guard()->checks()},
                                                                   {"per_tet_passes", fast->guard()->tet_passes()},
                                                                   {"renewals", fast->guard()->full_checks()}}
                                                  : nlohmann::json(nullptr)},
                          {"newton_tolerance_m", opt.newton_tolerance},
                          {"cache", reduced_model->cache_outcome},
                          {"factorizations", total.factorizations},
                          {"model_seconds", reduced_model->build_seconds}};
  }
  summary["dynamics"] = writer.dynamics_summary();
  summary["frames"] = frames;
  const double steps = static_cast<double>(motion.num_frames() > 0 ? motion.num_frames() - 1 : 0);
  summary["timings"] = {{"build_seconds", build_seconds},
                        {"solve_seconds", solve_seconds},
                        {"function_seconds", total.function_seconds},
                        {"jacobian_seconds", total.jacobian_seconds},
                        {"model_seconds", model_seconds},
                        {"elastic_seconds", total.elastic_seconds},
                        {"inertia_seconds", total.inertia_seconds},
                        {"potential_seconds", total.potential_seconds},
                        {"dense_solve_seconds", total.solve_seconds},
                        {"output_seconds", output_seconds},
                        {"posing_seconds", writer.posing_seconds()},
                        {"writer_seconds", jobs ? jobs->busy_seconds() : 0.0},
                        {"writer_wait_seconds", jobs ? jobs->waited_seconds() : 0.0},
                        {"frames_per_second", solve_seconds > 0 ? steps / solve_seconds : 0.0},
                        {"seconds_per_frame", steps > 0 ? solve_seconds / steps : 0.0},
                        {"total_seconds", seconds_since(t_start)}};
  return summary;
}

}  // namespace sflsh::app
