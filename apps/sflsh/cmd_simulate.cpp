// sflsh simulate --solver full|reduced: the full-space reference solver or the reduced model on a subject's
// soft-tissue layer driven by a motion. Both write the posed body surface per frame exactly as `sflsh motion export` does (same points,
// same order, same .pvd layout), so that subtracting the two gives the soft-tissue motion.
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <optional>

namespace sflsh::app {

namespace {

struct SimulateOptions {
  std::string solver = "full";
  SubjectOptions subject;
  std::string motion;
  int frames = 0;
  double fps = 60.0;
  int substeps = 1;
  std::string mesh = "default";
  LayerSettings layer;                       ///< mesher, material, cache, density, gravity, stiffness, mass
  std::string integrator = "backward_euler";   ///< backward_euler | bdf2 | newmark (time_integrator.hpp)
  bool write_layer = false;
  bool no_output = false;
  int every = 1;                             ///< write every N-th frame (the first and the last always)
  std::string out;
  // Reduced model.
  int handles = 86;
  int cubature = -1;
  std::string cubature_weights = "nnls";
  bool affine = false;
  // Scene files.
  std::string scene;
  int threads = 0;
  bool every_given = false;                  ///< --every overrides the scene's [output] every
};

// sflsh simulate --scene FILE: bodies, objects and the effects the scene calls for (scene_runner.hpp).
void run_scene_file(const SimulateOptions& opt, const Invocation& invocation, int rank) {
  const scene::Scene scene = scene::load_scene(opt.scene);
  scene::SceneRunOptions options;
  options.frames = opt.frames;
  options.out = opt.out;
  options.cache_dir = opt.layer.cache;
  options.threads = opt.threads;
  options.write_frames = !opt.no_output;
  options.every = opt.every_given ? opt.every : 0;
  options.rank = rank;
  options.header = summary_header("simulate", invocation.argc, invocation.argv);
  const nlohmann::json summary = scene::run_scene(scene, options);
  if (rank != 0) return;
  std::string effects;
  for (const auto& e : summary["effects"]) effects += fmt::format("{}{} {:.2f} s", effects.empty() ? "" : ", ", e["name"].get<std::string>(),
                                                                  e["seconds"].get<double>());
  logger()->info("scene '{}': {} frames in {:.1f} s ({}); wrote {}", scene.name, summary["scene"]["frames"].get<int>(),
                 summary["timings"]["loop_seconds"].get<double>(), effects, opt.out);
}

void run_simulate(const SimulateOptions& opt, const Invocation& invocation, int rank, int size) {
  require(opt.every >= 1, "--every must be at least 1, got {}", opt.every);
  if (!opt.scene.empty()) return run_scene_file(opt, invocation, rank);
  require(!opt.motion.empty(), "simulate: --motion is required (or give a scene with --scene FILE)");
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
  const body::Motion motion = body::load_motion(opt.motion, opt.fps, opt.frames);
  motion.validate();

  const std::optional<material::MaterialFile> material_file = load_layer_material(opt.layer);
  const model::BodyLayerOptions layer_options = body_layer_options(opt.layer, opt.mesh);
  const auto t_build = Clock::now();
  model::BodyLayer layer = model::build_body_layer(model, beta, motion, material_file ? &*material_file : nullptr,
                                                   opt.layer.control_points, layer_options);
  const double build_seconds = seconds_since(t_build);
  const model::Problem& problem = layer.problem;
  logger()->info(
      "simulate: {} nodes ({} free), {} tets, {} frames at {} fps, {} substep(s), {} + {} mass, {} process(es)",
      problem.num_nodes(), problem.num_nodes() - static_cast<int>(problem.dirichlet.dof.size() / 3), problem.num_tets(),
      motion.num_frames(), motion.fps, opt.substeps, model::to_string(integrator), model::to_string(problem.mass_kind),
      size);

  const bool use_reduced = opt.solver == "reduced";
  require(!use_reduced || size == 1, "--solver reduced runs on one process (got {}); parallelize over bodies instead", size);
  std::optional<reduced::ReducedModel> reduced_model;
  std::unique_ptr<fullspace::FullSpaceSolver> full;
  std::unique_ptr<reduced::ReducedSolver> fast;
  const auto t_model = Clock::now();
  if (use_reduced) {
    reduced::ReducedModelOptions ro;
    ro.point_handles = opt.handles;
    ro.cubature = opt.cubature;
    ro.weighting = opt.cubature_weights == "voronoi" ? reduced::CubatureWeighting::voronoi : reduced::CubatureWeighting::nnls;
    ro.basis.affine = opt.affine;
    if (!opt.layer.cache.empty()) ro.cache_dir = opt.layer.cache;
    reduced_model = reduced::build_reduced_model(layer, ro);
    reduced::ReducedOptions solver_options;
    solver_options.integrator = integrator;
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
  model::BodySolver& solver = use_reduced ? static_cast<model::BodySolver&>(*fast) : *full;

  const bool write = rank == 0 && !opt.no_output;
  std::optional<RunFolder> run;
  if (rank == 0) run.emplace(opt.out);
  // Declared after the run folder: a failing run drops its pending writes before the folder is removed.
  std::optional<BackgroundJobs> jobs;
  if (write) jobs.emplace(8);
  model::SimulationWriterOptions writer_options;
  writer_options.write_layer = opt.write_layer;
  writer_options.jobs = jobs ? &*jobs : nullptr;
  model::SimulationWriter writer(layer, write ? &*run : nullptr, writer_options);
  const int num_frames = static_cast<int>(motion.num_frames());
  writer.add_frame(0, 0.0, solver.current_state(), true);

  nlohmann::json frames = nlohmann::json::array();
  frames.push_back({{"frame", 0}, {"t", 0.0}, {"newton_iterations", 0}, {"linear_iterations", 0}, {"seconds", 0.0}});
  const double h = 1.0 / (motion.fps * opt.substeps);
  Progress progress("frames", motion.num_frames() > 0 ? motion.num_frames() - 1 : 0, rank == 0);
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
  });
  progress.finish();
  const double solve_seconds = total.seconds;
  if (rank != 0) return;

  const auto t_drain = Clock::now();
  if (jobs) jobs->wait();
  output_seconds += seconds_since(t_drain);
  writer.finish();
  nlohmann::json summary = summary_header("simulate", invocation.argc, invocation.argv);
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
                       {"failed_attempts", total.failed_attempts}};
  summary["body"] = opt.subject.body_path.empty() ? "open_body" : opt.subject.body_path;
  summary["subject"] = subject_label;
  summary["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  summary["motion"] = {{"name", motion.name}, {"source", motion.source}, {"fps", motion.fps}, {"frames", motion.num_frames()}};
  summary["mesh"] = {{"mesher", opt.layer.mesher}, {"size", opt.mesh}, {"nodes", problem.num_nodes()},
                     {"tets", problem.num_tets()}, {"constrained_dofs", problem.dirichlet.dof.size()}};
  summary["material"] = material_summary(opt.layer, material_file);
  if (reduced_model) {
    summary["reduced"] = {{"point_handles", reduced_model->handles.point_nodes.size()},
                          {"bone_handles", reduced_model->handles.bone_joints().size()},
                          {"affine", opt.affine},
                          {"coordinates", reduced_model->subspace.num_dofs()},
                          {"basis_nonzeros", reduced_model->subspace.basis.nonZeros()},
                          {"cubature", reduced_model->cubature.size()},
                          {"cubature_method", reduced_model->cubature.method},
                          {"cache", reduced_model->cache_outcome},
                          {"factorizations", total.factorizations},
                          {"model_seconds", reduced_model->build_seconds}};
  }
  summary["dynamics"] = writer.dynamics_summary();
  summary["frames"] = frames;
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
                        {"frames_per_second", solve_seconds > 0 ? static_cast<double>(motion.num_frames() - 1) / solve_seconds : 0.0},
                        {"seconds_per_frame", motion.num_frames() > 1 ? solve_seconds / static_cast<double>(motion.num_frames() - 1) : 0.0},
                        {"total_seconds", seconds_since(t_start)}};
  summary["output"] = opt.no_output ? nlohmann::json("summary.json only")
                                    : nlohmann::json({{"series", "body.pvd"}, {"layer", opt.write_layer ? "layer.pvd" : ""},
                                                      {"every", opt.every}, {"compression", vtk::to_string(writer_options.compression)}});
  write_json(run->stage("summary.json"), summary);
  run->commit();
  logger()->info("simulated {} frames in {:.1f} s ({:.3f} s per frame); mean σ = {:.2f} mm", motion.num_frames(),
                 solve_seconds, motion.num_frames() > 1 ? solve_seconds / static_cast<double>(motion.num_frames() - 1) : 0.0,
                 writer.dynamics_summary().value("sigma_mean_mm", 0.0));
}

}  // namespace

void register_simulate_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<SimulateOptions>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Simulate a subject's soft tissue along a motion and write the posed body surface per frame (as "
      "`sflsh motion export` does). PETSc options (-snes_*, -ksp_*, -pc_*) may follow; parallel with mpirun -n P.");
  cmd->add_option("--solver", opt->solver, "Solver: full (the full-space reference) | reduced (handles + cubature)")
      ->check(CLI::IsMember({"full", "reduced"}));
  cmd->add_option("--handles", opt->handles, "Reduced: point handles inside the layer (plus the 24 bone handles)");
  cmd->add_option("--cubature", opt->cubature, "Reduced: cubature tets K (default −1 = auto: max(200, 0.8 × coordinates); 0 = every tet, exact)");
  cmd->add_option("--cubature-weights", opt->cubature_weights, "Reduced: nnls (training-free force matching) | voronoi")
      ->check(CLI::IsMember({"nnls", "voronoi"}));
  cmd->add_flag("--affine", opt->affine, "Reduced: affine point handles (12 coordinates each instead of 3)");
  add_body_option(*cmd, opt->subject);
  add_subject_options(*cmd, opt->subject);
  cmd->add_option("--scene", opt->scene,
                  "Scene file (TOML, docs/scenes.md, data/scenes/): bodies, objects and effects; then only --frames, --every, "
                  "--out, --cache, --threads and --no-output apply")
      ->check(CLI::ExistingFile);
  cmd->add_option("--threads", opt->threads, "Scenes: threads for bodies that do not interact (0: all cores)");
  cmd->add_option("--motion", opt->motion, "Motion: a procedural name (sflsh motion list) or an AMASS .npz path (required without --scene)");
  cmd->add_option("--frames", opt->frames, "Number of frames (0: the motion's length)");
  cmd->add_option("--fps", opt->fps, "Frame rate of the output (and of the motion sampling)");
  cmd->add_option("--substeps", opt->substeps, "Integrator steps per frame (step = 1 / (fps · substeps))");
  cmd->add_option("--integrator", opt->integrator,
                  "Time integrator: backward_euler (default; first order, damps) | bdf2 (second order, mild damping) | "
                  "newmark (trapezoidal, no numerical damping); docs/integrators.md");
  cmd->add_option("--mesh", opt->mesh, "Layer resolution: coarse | default | fine")
      ->check(CLI::IsMember({"coarse", "default", "fine"}));
  add_layer_options(*cmd, opt->layer);
  add_mass_option(*cmd, opt->layer);
  cmd->add_flag("--write-layer", opt->write_layer, "Also write the tet layer per frame (layer.pvd)");
  cmd->add_flag("--no-output", opt->no_output, "Write only summary.json");
  cmd->add_option("--every", opt->every,
                  "Write every N-th frame (frame 0 and the last frame always; σ and the summary still use every frame); "
                  "with --scene it overrides [output] every")
      ->each([opt](const std::string&) { opt->every_given = true; });
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] {
    with_petsc(invocation, [&](int rank, int size) { run_simulate(*opt, invocation, rank, size); });
  });
}

}  // namespace sflsh::app
