// One body along a motion, frame by frame (body_simulation.hpp): the settings are checked and the work estimated
// before anything large is built, then the layer, the solver (full space on PETSc or the reduced model) and the
// writer; step() runs one output frame through the shared frame loop and records it.
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/work_limit.hpp>
#include <sflsh/core/xdmf_series.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_settings.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/run/body_simulation.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::run {

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

SolverChoice solver_choice(const BodyRunSettings& opt) {
  SolverChoice choice;
  // The SUNDIALS reference is not offered here (`sflsh tradeoff --reference sundials` runs it).
  require(opt.solver == "full" || opt.solver == "reduced", "--solver {}: expected full or reduced", opt.solver);
  choice.kind = parse_solver_kind(opt.solver, "--solver");
  choice.integrator = model::parse_integrator(opt.integrator, "--integrator");
  choice.handles = opt.handles;
  choice.cubature = opt.cubature;
  choice.reduced_settings.cubature_weights = opt.cubature_weights;
  choice.reduced_settings.affine = opt.affine;
  choice.newton_tolerance = opt.newton_tolerance;
  check_solver_choice(choice);
  return choice;
}

BodySimulation::BodySimulation(const BodyRunSettings& opt, RunFolder* frames_to, int rank, int size,
                               const BodyRunReporting& reporting)
    : settings_(opt), reporting_(reporting), rank_(rank), size_(size), t_start_(Clock::now()) {
  choice_ = solver_choice(opt);  // the solver's settings parsed and checked once, before anything is loaded
  // Both bounds in every message (issue 45); 10⁴ fps as a scene's fps.
  require(opt.fps > 0.0 && opt.fps <= 1e4, "--fps must be in (0, 10000] frames per second, got {}", opt.fps);
  require(opt.substeps >= 1 && opt.substeps <= 1'000'000, "--substeps must be an integer in [1, 10⁶], got {}",
          opt.substeps);
  require(opt.frames >= 0, "--frames must be non-negative, got {}", opt.frames);
  model::check_layer_settings(opt.layer);

  body_ = std::make_unique<body::BodyModel>(body::load_selected_body(opt.subject));
  beta_ = body::selected_betas(opt.subject, subject_label_, "simulate");
  // Before the motion is sampled (frames × 600 B) or anything is built: --frames and --substeps as given …
  check_body_run_work(opt, opt.frames);
  motion_ = body::load_motion(opt.motion, opt.fps, opt.frames);
  motion_.validate();
  check_body_run_work(opt, static_cast<double>(motion_.num_frames()));  // … and with the motion's own length

  if (opt.material_data)
    material_file_ = *opt.material_data;
  else
    material_file_ = model::load_layer_material(opt.layer);
  const model::BodyLayerOptions layer_options = model::body_layer_options(opt.layer, opt.mesh);
  const auto t_build = Clock::now();
  layer_ = std::make_unique<model::BodyLayer>(model::build_body_layer(
      *body_, beta_, motion_, material_file_ ? &*material_file_ : nullptr, opt.layer.control_points, layer_options));
  build_seconds_ = seconds_since(t_build);
  const model::Problem& problem = layer_->problem;
  logger()->log(
      reporting.log_details ? spdlog::level::info : spdlog::level::debug,
      "simulate: {} nodes ({} free), {} tets, {} frames at {} fps, {} substep(s), {} + {} mass, {} process(es)",
      problem.num_nodes(), problem.num_nodes() - static_cast<int>(problem.dirichlet.dof.size() / 3), problem.num_tets(),
      motion_.num_frames(), motion_.fps, opt.substeps, model::to_string(choice_.integrator),
      model::to_string(problem.mass_kind), size);

  const SolverChoice& choice = choice_;
  require(choice.kind != SolverKind::reduced || size == 1,
          "--solver reduced runs on one process (got {}); parallelize over bodies instead", size);
  const auto t_model = Clock::now();
  if (choice.kind == SolverKind::reduced)
    reduced_model_ = std::make_unique<reduced::ReducedModel>(make_reduced_model(*layer_, choice, opt.layer.cache));
  solver_ = make_body_solver(problem, choice, model::initial_state(problem, 0.0),
                             reduced_model_ ? parts_of(*reduced_model_) : ReducedParts{});
  model_seconds_ = seconds_since(t_model);
  if (reporting.on_setup)
    reporting.on_setup({{"tets", problem.num_tets()},
                        {"coordinates", reduced_model_ ? reduced_model_->subspace.num_dofs() : 0},
                        {"cubature", reduced_model_ ? reduced_model_->cubature.size() : 0}});

  const bool write = rank == 0 && frames_to != nullptr;
  if (write) jobs_.emplace(8);
  writer_options_ = frame_writer_options(opt);
  writer_options_.jobs = jobs_ ? &*jobs_ : nullptr;
  writer_ = std::make_unique<model::SimulationWriter>(*layer_, write ? frames_to : nullptr, writer_options_);
  writer_->add_frame(0, 0.0, solver_->current_state(), true);
  frames_.push_back({{"frame", 0}, {"t", 0.0}, {"newton_iterations", 0}, {"linear_iterations", 0}, {"seconds", 0.0}});
}

BodySimulation::~BodySimulation() = default;

const model::StepStats& BodySimulation::step() {
  require(!finished(), "simulate: the motion has {} frames; frame {} is its last", num_frames(), frame_);
  require(!finished_output_, "simulate: the run was finished; no frame can follow");
  const auto t_step = Clock::now();
  model::FrameLoopOptions loop;
  loop.frames = frame_ + 2;
  loop.first_frame = frame_ + 1;
  loop.fps = motion_.fps;
  loop.substeps = settings_.substeps;
  const model::Problem& problem = layer_->problem;
  model::run_frames(*solver_.solver, loop, [&](int frame, double, const model::StepStats& st) {
    const auto f = static_cast<std::size_t>(frame);
    const auto t_output = Clock::now();
    const bool written = model::is_written_frame(frame, num_frames(), settings_.every);
    // The skin's fields and σ need x alone; the velocities (and the motion's node maps behind them) only for the tet
    // layer's frames and the energies.
    const bool full_state = settings_.energies || (written && settings_.write_layer);
    model::State state;
    if (full_state) {
      state = solver_->current_state();
      writer_->add_frame(frame, motion_.time(f), state, written);
    } else {
      writer_->add_positions(frame, motion_.time(f), solver_->positions(), written);
    }
    nlohmann::json record = {{"frame", f},
                             {"t", motion_.time(f)},
                             {"newton_iterations", st.newton_iterations},
                             {"linear_iterations", st.linear_iterations},
                             {"failed_attempts", st.failed_attempts},
                             {"seconds", st.seconds}};
    if (settings_.energies) {
      const model::Energies e = model::energies(problem, state);
      record["energy"] = {{"kinetic", e.kinetic}, {"elastic", e.elastic}, {"gravity", e.gravity}};
    }
    output_seconds_ += seconds_since(t_output);
    frames_.push_back(std::move(record));
    model::accumulate(total_, st);
    last_ = st;
    frame_ = frame;
  });
  last_step_seconds_ = seconds_since(t_step);
  return last_;
}

model::State BodySimulation::state() const { return solver_->current_state(); }

model::RowMatrixX3d BodySimulation::posed_surface() const {
  return layer_->posed_surface(solver_->current_state().x, time());
}

model::RowMatrixX3d BodySimulation::skinned_surface() const {
  const int region = layer_->mesh->region_surface.num_vertices();
  return layer_->posed_surface_from_displacement(model::RowMatrixX3d::Zero(region, 3), time());
}

}  // namespace sflsh::run
