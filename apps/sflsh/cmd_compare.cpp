// sflsh compare: the full-space reference against a sweep of reduced models (handles × cubature) on the same
// subject, motion and parameters. Reports the dynamics amplitude σ per vertex of each (docs/physics.md §4), the
// fraction of the full-space dynamics each reduced model recovers, per-vertex error maps, the time per frame
// and the error–time trade-off (tradeoff.csv / .md / .png, compare.vtp, summary.json).
#include "commands.hpp"
#include "compare_report.hpp"
#include "layer_setup.hpp"
#include "simulate_run.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

namespace sflsh::app {

namespace {

struct CompareOptions {
  SubjectOptions subject;
  std::string motion;
  int frames = 0;
  double fps = 60.0;
  int substeps = 1;
  std::string mesh = "default";
  LayerSettings layer;
  std::string integrator = scene::BodyRunSettings().integrator;  ///< both solvers' (time_integrator.hpp)
  std::string handles = "30,86,200";
  std::string cubature = "100,200,400";
  bool exact_cubature = false;
  ReducedSettings reduced;
  std::string out;
};

/// "30,86,200" → {30, 86, 200}: distinct, in the given order, each at least `minimum`.
std::vector<int> parse_sweep(const std::string& text, const char* option, int minimum) {
  std::vector<int> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    if (first == std::string::npos) continue;
    item = item.substr(first, last - first + 1);
    std::size_t used = 0;
    int v = 0;
    if (minimum == 0 && item == "auto") {  // the cubature the reduced model picks itself (reduced_model.hpp)
      if (std::find(values.begin(), values.end(), -1) == values.end()) values.push_back(-1);
      continue;
    }
    try {
      v = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == item.size() && used > 0, "{} {}: '{}' is not a whole number", option, text, item);
    require(v >= minimum, "{} {}: {} is below {}", option, text, v, minimum);
    if (std::find(values.begin(), values.end(), v) == values.end()) values.push_back(v);
  }
  require(!values.empty(), "{}: the sweep is empty (expected a comma-separated list such as {})", option,
          minimum == 0 ? "100,200,400" : "30,86,200");
  return values;
}

/// One reduced configuration of the sweep and what its run measured.
struct Configuration {
  int handles = 0;
  int cubature_request = 0;  ///< 0 = every tet
  int cubature_tets = 0;     ///< tets in use at the end (the model's, plus any the guard added)
  reduced::ReducedModel model;
  int frames = 0;
  double seconds = 0.0, elastic_seconds = 0.0, inertia_seconds = 0.0, solve_seconds = 0.0;
  long newton = 0, retries = 0;
  Eigen::VectorXd sigma;        ///< per region vertex [m]
  Eigen::VectorXd error_sq;     ///< Σ_t |u − u_full|² per region vertex [m²]
  double trajectory_sq = 0.0;   ///< Σ over frames 1..F and region vertices of |p − p_full|² [m²]
  double trajectory_max = 0.0;  ///< max over frames 1..F and region vertices of |p − p_full| [m]
  std::string invalid;          ///< when and why the full-space state left the material's range
};

double per_frame(double total, int steps) { return steps > 0 ? total / steps : 0.0; }

/// Pearson correlation of two vectors (NaN when either is constant).
double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::ArrayXd da = a.array() - a.mean(), db = b.array() - b.mean();
  const double norm = std::sqrt((da * da).sum() * (db * db).sum());
  return norm > 0.0 ? (da * db).sum() / norm : std::nan("");
}

void run_compare(const CompareOptions& opt, const Invocation& invocation, int rank, int size) {
  const auto t_start = Clock::now();
  require(opt.fps > 0.0 && opt.fps <= 1e4, "--fps must be in (0, 10000] frames per second, got {}", opt.fps);
  require(opt.substeps >= 1 && opt.substeps <= 1'000'000, "--substeps must be an integer in [1, 10⁶], got {}",
          opt.substeps);
  require(opt.frames >= 0, "--frames must be non-negative, got {}", opt.frames);
  check_layer_settings(opt.layer);
  const model::Integrator integrator = model::parse_integrator(opt.integrator, "--integrator");
  const std::vector<int> handle_sweep = parse_sweep(opt.handles, "--handles", 1);
  std::vector<int> cubature_sweep = parse_sweep(opt.cubature, "--cubature", 0);
  if (opt.exact_cubature && std::find(cubature_sweep.begin(), cubature_sweep.end(), 0) == cubature_sweep.end())
    cubature_sweep.push_back(0);

  const body::BodyModel model = load_selected_body(opt.subject);
  std::string subject_label;
  const body::Betas beta = selected_betas(opt.subject, subject_label, "compare");
  const body::Motion motion = body::load_motion(opt.motion, opt.fps, opt.frames);
  motion.validate();
  require(motion.num_frames() >= 2, "compare: the motion has {} frame(s); at least 2 are needed", motion.num_frames());
  const std::optional<material::MaterialFile> material_file = load_layer_material(opt.layer);
  const auto t_build = Clock::now();
  const model::BodyLayer layer =
      model::build_body_layer(model, beta, motion, material_file ? &*material_file : nullptr, opt.layer.control_points,
                              body_layer_options(opt.layer, opt.mesh));
  const double build_seconds = seconds_since(t_build);
  const model::Problem& problem = layer.problem;
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  const auto R = static_cast<Eigen::Index>(region.size());
  const int steps = static_cast<int>(motion.num_frames()) - 1;
  const double h = 1.0 / (motion.fps * opt.substeps);

  // Every reduced model first (rank 0; cached beside the template mesh): a handle count the mesh cannot take
  // fails here, before the expensive reference run.
  std::vector<std::unique_ptr<Configuration>> configs;
  const auto t_models = Clock::now();
  check_handle_counts(layer, handle_sweep);  // all counts checked before any model is built (one message, no output)
  if (rank == 0) {
    for (int handles : handle_sweep) {
      for (int k : cubature_sweep) {
        auto c = std::make_unique<Configuration>();
        c->handles = handles;
        c->cubature_request = k;
        c->model = reduced::build_reduced_model(layer, reduced_model_options(opt.reduced, handles, k, opt.layer.cache));
        configs.push_back(std::move(c));
      }
    }
  }
  const double models_seconds = seconds_since(t_models);
  logger()->info(
      "compare: {} nodes, {} tets, {} region vertices, {} frames at {} fps; reference on {} process(es), {} reduced "
      "configuration(s)",
      problem.num_nodes(), problem.num_tets(), R, motion.num_frames(), motion.fps, size,
      handle_sweep.size() * cubature_sweep.size());

  // The full-space reference: its skin displacement per frame is kept for the error maps, its posed region surface
  // for the trajectory error.
  std::vector<model::RowMatrixX3d> u_full, posed_full;
  u_full.reserve(motion.num_frames());
  posed_full.reserve(motion.num_frames());
  auto posed_region = [&](const model::RowMatrixX3d& u, double t) {
    const model::RowMatrixX3d all = layer.posed_surface_from_displacement(u, t);
    model::RowMatrixX3d rows(R, 3);
    for (Eigen::Index r = 0; r < R; ++r) rows.row(r) = all.row(region[static_cast<std::size_t>(r)]);
    return rows;
  };
  const model::RowMatrixX3d normals = region_normals(layer);
  model::DynamicsAmplitude full_amplitude(normals);
  double full_seconds = 0.0;
  long full_newton = 0, full_linear = 0, full_retries = 0;
  {
    fullspace::FullSpaceOptions full_options;
    full_options.integrator = integrator;
    fullspace::FullSpaceSolver full(problem, MPI_COMM_WORLD, full_options);
    full.initialize(model::initial_state(problem, 0.0));
    u_full.push_back(layer.surface_displacement(full.state().x));
    Progress progress("full-space frames", static_cast<std::size_t>(steps), rank == 0);
    model::FrameLoopOptions loop;
    loop.frames = steps + 1;
    loop.fps = motion.fps;
    loop.substeps = opt.substeps;
    const model::StepStats total = model::run_frames(full, loop, [&](int f, double, const model::StepStats&) {
      const model::State& state = full.state();
      require(state.x.allFinite(), "compare: the full-space state at t = {} is not finite",
              motion.time(static_cast<std::size_t>(f)));
      u_full.push_back(layer.surface_displacement(state.x));
      progress.advance();
    });
    full_seconds = total.seconds;
    full_newton = total.newton_iterations;
    full_linear = total.linear_iterations;
    full_retries = total.failed_attempts;
  }
  for (const auto& u : u_full) full_amplitude.add(u);
  for (std::size_t f = 0; f < u_full.size(); ++f) posed_full.push_back(posed_region(u_full[f], motion.time(f)));
  const Eigen::VectorXd sigma_full = full_amplitude.sigma();
  double full_sq = 0.0;
  for (const auto& u : u_full) full_sq += u.squaredNorm();
  const double samples = static_cast<double>(R) * static_cast<double>(u_full.size());
  const double full_rms = std::sqrt(full_sq / samples);
  logger()->info("full space: {:.3f} s per frame, mean σ = {:.3f} mm", per_frame(full_seconds, steps),
                 1e3 * sigma_full.mean());
  if (rank != 0) return;

  // The reduced sweep, frame by frame against the stored reference. The full-space elastic energy of each
  // reduced state (outside the timing) checks that no tet left the material's range: a cubature too small
  // for its subspace stays stable on its own points while the tets it does not sample deform freely.
  Progress progress("reduced frames", configs.size() * static_cast<std::size_t>(steps));
  for (auto& cp : configs) {
    Configuration& c = *cp;
    reduced::ReducedOptions reduced_options;
    reduced_options.integrator = integrator;
    reduced::ReducedSolver fast(problem, c.model.subspace, c.model.cubature, reduced_options);
    fast.initialize(model::initial_state(problem, 0.0));
    model::DynamicsAmplitude amplitude(normals);
    c.error_sq = Eigen::VectorXd::Zero(R);
    // Named by the requested count (the per-function coverage may add a tet or two; every tet for exact cubature).
    const std::string name =
        compare::config_suffix(c.handles, c.cubature_request > 0 ? c.cubature_request : c.model.cubature.size());
    auto record = [&](std::size_t f) {
      const model::State state = fast.full_state();
      const model::RowMatrixX3d u = layer.surface_displacement(state.x);
      require(u.allFinite(), "compare: reduced {} state at t = {} is not finite", name, motion.time(f));
      amplitude.add(u);
      c.error_sq += (u - u_full[f]).rowwise().squaredNorm();
      if (f > 0) {
        const Eigen::VectorXd d2 = (posed_region(u, motion.time(f)) - posed_full[f]).rowwise().squaredNorm();
        c.trajectory_sq += d2.sum();
        c.trajectory_max = std::max(c.trajectory_max, std::sqrt(d2.maxCoeff()));
      }
      if (c.invalid.empty()) {
        try {
          (void)model::energies(problem, state);
        } catch (const Error& e) {
          c.invalid = fmt::format("at t = {:.4f} s: {}", motion.time(f), e.what());
          logger()->warn("reduced {}: the full-space state leaves the material's range {}", name, c.invalid);
        }
      }
    };
    record(0);
    model::FrameLoopOptions loop;
    loop.frames = steps + 1;
    loop.fps = motion.fps;
    loop.substeps = opt.substeps;
    const model::StepStats total = model::run_frames(fast, loop, [&](int f, double, const model::StepStats&) {
      record(static_cast<std::size_t>(f));
      progress.advance();
    });
    c.cubature_tets = fast.cubature().size();
    c.seconds = total.seconds;
    c.elastic_seconds = total.elastic_seconds;
    c.inertia_seconds = total.inertia_seconds;
    c.solve_seconds = total.solve_seconds;
    c.newton = total.newton_iterations;
    c.retries = total.failed_attempts;
    c.frames = steps;
    c.sigma = amplitude.sigma();
  }
  progress.finish();

  // The trade-off rows and the per-vertex maps.
  std::vector<compare::TradeoffRow> rows;
  compare::TradeoffRow full_row;
  full_row.seconds_per_frame = per_frame(full_seconds, steps);
  full_row.frames_per_second = full_seconds > 0 ? steps / full_seconds : 0.0;
  full_row.sigma_mean_mm = 1e3 * sigma_full.mean();
  full_row.recovered_fraction = 1.0;
  full_row.sigma_correlation = 1.0;
  rows.push_back(full_row);
  auto scatter = [&](const Eigen::VectorXd& region_values) {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(layer.shaped.rows(), 1);
    for (Eigen::Index r = 0; r < R; ++r) out(region[static_cast<std::size_t>(r)], 0) = region_values[r];
    return out;
  };
  vtk::Fields fields;
  fields.point_data.push_back({"sigma_full", scatter(1e3 * sigma_full), false});
  fields.point_data.push_back({"soft_region", scatter(Eigen::VectorXd::Ones(R)), true});
  fields.point_data.push_back({"region", scatter(Eigen::VectorXd::Ones(R)), true});  // soft_region's older name
  std::vector<compare::ReducedTimings> timings;
  nlohmann::json reduced_json = nlohmann::json::array();
  for (const auto& cp : configs) {
    const Configuration& c = *cp;
    compare::TradeoffRow row;
    row.reduced = true;
    row.handles = c.handles;
    row.cubature = c.cubature_request > 0 ? c.cubature_request : c.model.cubature.size();
    row.coordinates = c.model.subspace.num_dofs();
    row.seconds_per_frame = per_frame(c.seconds, c.frames);
    row.frames_per_second = c.seconds > 0 ? c.frames / c.seconds : 0.0;
    row.sigma_mean_mm = 1e3 * c.sigma.mean();
    row.recovered_fraction = sigma_full.mean() > 0 ? c.sigma.mean() / sigma_full.mean() : std::nan("");
    row.rms_error_mm = 1e3 * std::sqrt(c.error_sq.sum() / samples);
    row.relative_rms_error = full_rms > 0 ? std::sqrt(c.error_sq.sum() / samples) / full_rms : std::nan("");
    row.valid = c.invalid.empty();
    row.sigma_correlation = correlation(c.sigma, sigma_full);
    row.trajectory_rms_mm = 1e3 * std::sqrt(c.trajectory_sq / (static_cast<double>(R) * static_cast<double>(steps)));
    row.trajectory_max_mm = 1e3 * c.trajectory_max;
    rows.push_back(row);
    const std::string suffix = compare::config_suffix(row.handles, row.cubature);
    const Eigen::VectorXd rms_vertex = (c.error_sq / static_cast<double>(u_full.size())).cwiseSqrt();
    fields.point_data.push_back({"sigma_reduced_" + suffix, scatter(1e3 * c.sigma), false});
    fields.point_data.push_back({"sigma_error_" + suffix, scatter(1e3 * (c.sigma - sigma_full)), false});
    fields.point_data.push_back({"rms_error_" + suffix, scatter(1e3 * rms_vertex), false});
    compare::ReducedTimings t{row.handles,
                              row.cubature,
                              per_frame(c.elastic_seconds, c.frames),
                              per_frame(c.inertia_seconds, c.frames),
                              per_frame(c.solve_seconds, c.frames),
                              per_frame(static_cast<double>(c.newton), c.frames)};
    timings.push_back(t);
    reduced_json.push_back(
        {{"handles", row.handles},
         {"bone_handles", c.model.handles.bone_joints().size()},
         {"coordinates", row.coordinates},
         {"cubature", row.cubature},
         {"cubature_tets", c.cubature_tets},
         {"cubature_method", c.model.cubature.method},
         {"cache", c.model.cache_outcome},
         {"fields", {"sigma_reduced_" + suffix, "sigma_error_" + suffix, "rms_error_" + suffix}},
         {"seconds_per_frame", row.seconds_per_frame},
         {"frames_per_second", row.frames_per_second},
         {"elastic_seconds_per_frame", t.elastic_seconds_per_frame},
         {"inertia_seconds_per_frame", t.inertia_seconds_per_frame},
         {"solve_seconds_per_frame", t.solve_seconds_per_frame},
         {"newton_iterations", c.newton},
         {"failed_attempts", c.retries},
         {"speedup", row.seconds_per_frame > 0 ? full_row.seconds_per_frame / row.seconds_per_frame : 0.0},
         {"sigma_mean_mm", row.sigma_mean_mm},
         {"sigma_max_mm", 1e3 * c.sigma.maxCoeff()},
         {"recovered_fraction", row.recovered_fraction},
         {"rms_error_mm", row.rms_error_mm},
         {"max_vertex_rms_error_mm", 1e3 * rms_vertex.maxCoeff()},
         {"relative_rms_error", row.relative_rms_error},
         {"sigma_correlation", row.sigma_correlation},
         {"trajectory_rms_mm", row.trajectory_rms_mm},
         {"trajectory_max_mm", row.trajectory_max_mm},
         {"within_material_range", row.valid},
         {"out_of_range", c.invalid.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.invalid)}});
    logger()->info(
        "reduced {} handles, {} cubature tets: {:.2f} ms per frame ({:.0f}× faster), {:.0f}% of the dynamics, relative "
        "RMS error {:.3f}",
        row.handles, row.cubature, 1e3 * row.seconds_per_frame,
        row.seconds_per_frame > 0 ? full_row.seconds_per_frame / row.seconds_per_frame : 0.0,
        100.0 * row.recovered_fraction, row.relative_rms_error);
  }

  // Everything is computed: the run folder appears at once.
  RunFolder run(opt.out);
  vtk::write_surface(run.stage("compare.vtp"), layer.shaped, model.faces, fields);
  compare::write_tradeoff_csv(run.stage("tradeoff.csv"), rows);
  const std::string title = fmt::format("{} · {} · {} mesh · {} frames at {:g} fps", subject_label, motion.name,
                                        opt.mesh, motion.num_frames(), motion.fps);
  compare::write_tradeoff_markdown(
      run.stage("tradeoff.md"), "Full space against reduced models: " + title,
      {fmt::format("layer: {} nodes, {} tets, {} region vertices; step {:.4g} s", problem.num_nodes(),
                   problem.num_tets(), R, h),
       fmt::format("full space: {} Newton and {} linear iterations on {} process(es)", full_newton, full_linear, size),
       "σ: dynamics amplitude per vertex (docs/physics.md §4), mean over the region; recovered = mean σ / mean σ of "
       "the full space",
       "RMS error: of |u − u_full| over region vertices and frames; relative: divided by the RMS of u_full",
       "σ correlation: Pearson correlation of σ and σ_full over the region's vertices; trajectory RMS / max: of |p − "
       "p_full| over "
       "region vertices and frames 1..F, p the posed body surface that `sflsh simulate` writes"},
      rows, timings);
  std::string png = "tradeoff.png";
  try {
    compare::write_tradeoff_png(run.stage("tradeoff.png"), "Error against time: " + title, rows);
  } catch (const Error& e) {  // the picture is a convenience: the tables never depend on a display
    logger()->warn("skipped tradeoff.png: {}", e.what());
    png.clear();
  }

  nlohmann::json summary = summary_header("compare", invocation.argc, invocation.argv);
  summary["body"] = body::body_label(opt.subject);
  summary["subject"] = subject_label;
  summary["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  summary["motion"] = {
      {"name", motion.name}, {"source", motion.source}, {"fps", motion.fps}, {"frames", motion.num_frames()}};
  summary["mesh"] = {{"mesher", opt.layer.mesher},
                     {"size", opt.mesh},
                     {"nodes", problem.num_nodes()},
                     {"tets", problem.num_tets()},
                     {"constrained_dofs", problem.dirichlet.dof.size()},
                     {"region_vertices", R},
                     {"body_vertices", model.num_vertices()}};
  summary["material"] = material_summary(opt.layer, material_file);
  summary["step"] = h;
  summary["substeps"] = opt.substeps;
  summary["integrator"] = model::to_string(integrator);
  summary["mass"] = opt.layer.mass;
  summary["sweep"] = {{"handles", handle_sweep},
                      {"cubature", cubature_sweep},
                      {"cubature_weights", opt.reduced.cubature_weights},
                      {"affine", opt.reduced.affine}};
  summary["full"] = {{"processes", size},
                     {"free_dofs", problem.num_dofs() - static_cast<int>(problem.dirichlet.dof.size())},
                     {"seconds_per_frame", full_row.seconds_per_frame},
                     {"frames_per_second", full_row.frames_per_second},
                     {"newton_iterations", full_newton},
                     {"linear_iterations", full_linear},
                     {"failed_attempts", full_retries},
                     {"sigma_mean_mm", full_row.sigma_mean_mm},
                     {"sigma_max_mm", 1e3 * sigma_full.maxCoeff()},
                     {"displacement_rms_mm", 1e3 * full_rms}};
  summary["reduced"] = reduced_json;
  summary["timings"] = {
      {"build_seconds", build_seconds}, {"models_seconds", models_seconds}, {"total_seconds", seconds_since(t_start)}};
  summary["output"] = {{"fields", "compare.vtp"},
                       {"table", "tradeoff.csv"},
                       {"markdown", "tradeoff.md"},
                       {"plot", png.empty() ? nlohmann::json(nullptr) : nlohmann::json(png)}};
  summary["units"] = {{"sigma", "mm"},
                      {"rms_error", "mm"},
                      {"trajectory_rms", "mm"},
                      {"trajectory_max", "mm"},
                      {"seconds_per_frame", "s"}};
  write_json(run.stage("summary.json"), summary);
  run.commit();
  logger()->info("compare: wrote {} ({} configurations, {:.1f} s)", run.dir().string(), configs.size(),
                 seconds_since(t_start));
}

}  // namespace

void register_compare_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<CompareOptions>();
  auto* cmd = app.add_subcommand(
      "compare",
      "Run the full-space reference and a sweep of reduced models (handles × cubature) on the same subject and motion; "
      "write σ and error maps (compare.vtp) and the error–time trade-off (tradeoff.csv, .md, .png).");
  add_body_option(*cmd, opt->subject);
  add_subject_options(*cmd, opt->subject);
  cmd->add_option("--motion", opt->motion, "Motion: a procedural name (sflsh motion list) or an AMASS .npz path")
      ->required();
  cmd->add_option("--frames", opt->frames, "Number of frames (0: the motion's length)");
  cmd->add_option("--fps", opt->fps, "Frame rate (and motion sampling)")->capture_default_str();
  cmd->add_option("--substeps", opt->substeps, "Integrator steps per frame for both solvers");
  add_integrator_option(*cmd, opt->integrator);
  add_mass_option(*cmd, opt->layer);
  cmd->add_option("--mesh", opt->mesh, "Layer resolution: coarse | default | fine")
      ->capture_default_str()
      ->check(CLI::IsMember({"coarse", "default", "fine"}));
  cmd->add_option("--handles", opt->handles, "Sweep of point-handle counts, comma-separated (plus the bone handles)")
      ->capture_default_str();
  cmd->add_option("--cubature", opt->cubature,
                  "Sweep of cubature tet counts K, comma-separated (0 = every tet; auto = the automatic count that "
                  "covers the subspace)")
      ->capture_default_str();
  cmd->add_flag("--exact-cubature", opt->exact_cubature, "Also run every handle count with exact cubature (every tet)");
  add_reduced_options(*cmd, opt->reduced);
  add_layer_options(*cmd, opt->layer);
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] {
    with_petsc(invocation, [&](int rank, int size) { run_compare(*opt, invocation, rank, size); });
  });
}

}  // namespace sflsh::app
