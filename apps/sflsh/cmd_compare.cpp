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
#include <sflsh/run/body_solver_factory.hpp>

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
  std::string mesh{run::kDefaultMesh};
  LayerSettings layer;
  std::string integrator = run::BodyRunSettings().integrator;  ///< both solvers' (time_integrator.hpp)
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

/// The region's rows of the posed body surface of skin displacement u at time t.
model::RowMatrixX3d posed_region(const model::BodyLayer& layer, const model::RowMatrixX3d& u, double t) {
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  const model::RowMatrixX3d all = layer.posed_surface_from_displacement(u, t);
  model::RowMatrixX3d rows(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r) rows.row(static_cast<Eigen::Index>(r)) = all.row(region[r]);
  return rows;
}

/// What a comparison runs on: the checked options, the subject's layer and the motion. Not movable: the layer refers
/// to the body model.
struct CompareCase {
  const CompareOptions& opt;
  model::Integrator integrator = model::kDefaultIntegrator;
  std::vector<int> handle_sweep, cubature_sweep;
  body::BodyModel model;
  std::string subject_label;
  body::Betas beta;
  body::Motion motion;
  std::optional<material::MaterialFile> material_file;
  model::BodyLayer layer;
  double build_seconds = 0.0;
  int steps = 0;             ///< frames after the first
  double h = 0.0;            ///< integrator step [s]
  Eigen::Index regions = 0;  ///< region vertices

  explicit CompareCase(const CompareOptions& options) : opt(options) {}
  CompareCase(const CompareCase&) = delete;
  CompareCase& operator=(const CompareCase&) = delete;

  /// The reduced solver of one configuration of the sweep (run/solver_choice.hpp).
  run::SolverChoice reduced_choice(int handles, int cubature) const {
    run::SolverChoice choice;
    choice.kind = run::SolverKind::reduced;
    choice.integrator = integrator;
    choice.handles = handles;
    choice.cubature = cubature;
    choice.reduced_settings = opt.reduced;
    return choice;
  }

  model::FrameLoopOptions frame_loop() const {
    model::FrameLoopOptions loop;
    loop.frames = steps + 1;
    loop.fps = motion.fps;
    loop.substeps = opt.substeps;
    return loop;
  }
};

/// Checks the options and builds the subject's layer for the motion (every input error before any solve).
void prepare_case(CompareCase& c) {
  const CompareOptions& opt = c.opt;
  require(opt.fps > 0.0 && opt.fps <= 1e4, "--fps must be in (0, 10000] frames per second, got {}", opt.fps);
  require(opt.substeps >= 1 && opt.substeps <= 1'000'000, "--substeps must be an integer in [1, 10⁶], got {}",
          opt.substeps);
  require(opt.frames >= 0, "--frames must be non-negative, got {}", opt.frames);
  check_layer_settings(opt.layer);
  c.integrator = model::parse_integrator(opt.integrator, "--integrator");
  c.handle_sweep = parse_sweep(opt.handles, "--handles", 1);
  c.cubature_sweep = parse_sweep(opt.cubature, "--cubature", 0);
  if (opt.exact_cubature && std::find(c.cubature_sweep.begin(), c.cubature_sweep.end(), 0) == c.cubature_sweep.end())
    c.cubature_sweep.push_back(0);

  c.model = load_selected_body(opt.subject);
  c.beta = selected_betas(opt.subject, c.subject_label, "compare");
  c.motion = body::load_motion(opt.motion, opt.fps, opt.frames);
  c.motion.validate();
  require(c.motion.num_frames() >= 2, "compare: the motion has {} frame(s); at least 2 are needed",
          c.motion.num_frames());
  c.material_file = load_layer_material(opt.layer);
  const auto t_build = Clock::now();
  c.layer = model::build_body_layer(c.model, c.beta, c.motion, c.material_file ? &*c.material_file : nullptr,
                                    opt.layer.control_points, body_layer_options(opt.layer, opt.mesh));
  c.build_seconds = seconds_since(t_build);
  c.regions = static_cast<Eigen::Index>(c.layer.mesh->region_surface.vertices.size());
  c.steps = static_cast<int>(c.motion.num_frames()) - 1;
  c.h = 1.0 / (c.motion.fps * opt.substeps);
}

/// Every reduced model of the sweep (rank 0; cached beside the template mesh): a handle count the mesh cannot take
/// fails here, before the expensive reference run.
std::vector<std::unique_ptr<Configuration>> build_configurations(const CompareCase& c, int rank) {
  check_handle_counts(c.layer, c.handle_sweep);  // all counts checked before any model is built (one message)
  std::vector<std::unique_ptr<Configuration>> configs;
  if (rank != 0) return configs;
  for (int handles : c.handle_sweep)
    for (int k : c.cubature_sweep) {
      auto config = std::make_unique<Configuration>();
      config->handles = handles;
      config->cubature_request = k;
      config->model = run::make_reduced_model(c.layer, c.reduced_choice(handles, k), c.opt.layer.cache);
      configs.push_back(std::move(config));
    }
  return configs;
}

/// The full-space reference run: its skin displacement per frame (kept for the error maps) and its posed region
/// surface (for the trajectory error).
struct FullReference {
  std::vector<model::RowMatrixX3d> u, posed;
  Eigen::VectorXd sigma;  ///< per region vertex [m]
  double rms = 0.0;       ///< RMS of u over region vertices and frames [m]
  double samples = 0.0;   ///< region vertices × frames
  model::StepStats total;
};

FullReference run_full_reference(const CompareCase& c, int rank) {
  FullReference full;
  full.u.reserve(c.motion.num_frames());
  full.posed.reserve(c.motion.num_frames());
  run::SolverChoice choice;
  choice.integrator = c.integrator;
  const run::BuiltSolver built =
      run::make_body_solver(c.layer.problem, choice, model::initial_state(c.layer.problem, 0.0));
  const fullspace::FullSpaceSolver& solver = *built.full;
  full.u.push_back(c.layer.surface_displacement(solver.state().x));
  Progress progress("full-space frames", static_cast<std::size_t>(c.steps), rank == 0);
  full.total = model::run_frames(*built, c.frame_loop(), [&](int f, double, const model::StepStats&) {
    const model::State& state = solver.state();
    require(state.x.allFinite(), "compare: the full-space state at t = {} is not finite",
            c.motion.time(static_cast<std::size_t>(f)));
    full.u.push_back(c.layer.surface_displacement(state.x));
    progress.advance();
  });
  model::DynamicsAmplitude amplitude(region_normals(c.layer));
  double sum_sq = 0.0;
  for (std::size_t f = 0; f < full.u.size(); ++f) {
    amplitude.add(full.u[f]);
    full.posed.push_back(posed_region(c.layer, full.u[f], c.motion.time(f)));
    sum_sq += full.u[f].squaredNorm();
  }
  full.sigma = amplitude.sigma();
  full.samples = static_cast<double>(c.regions) * static_cast<double>(full.u.size());
  full.rms = std::sqrt(sum_sq / full.samples);
  return full;
}

/// One reduced configuration, frame by frame against the stored reference. The full-space elastic energy of each
/// reduced state (outside the timing) checks that no tet left the material's range: a cubature too small for its
/// subspace stays stable on its own points while the tets it does not sample deform freely.
void run_configuration(Configuration& config, const CompareCase& c, const FullReference& full, Progress& progress) {
  const model::Problem& problem = c.layer.problem;
  const run::BuiltSolver built =
      run::make_body_solver(problem, c.reduced_choice(config.handles, config.cubature_request),
                            model::initial_state(problem, 0.0), run::parts_of(config.model));
  const reduced::ReducedSolver& solver = *built.reduced;
  model::DynamicsAmplitude amplitude(region_normals(c.layer));
  config.error_sq = Eigen::VectorXd::Zero(c.regions);
  // Named by the requested count (the per-function coverage may add a tet or two; every tet for exact cubature).
  const std::string name = compare::config_suffix(
      config.handles, config.cubature_request > 0 ? config.cubature_request : config.model.cubature.size());
  auto record = [&](std::size_t f) {
    const model::State state = solver.full_state();
    const model::RowMatrixX3d u = c.layer.surface_displacement(state.x);
    require(u.allFinite(), "compare: reduced {} state at t = {} is not finite", name, c.motion.time(f));
    amplitude.add(u);
    config.error_sq += (u - full.u[f]).rowwise().squaredNorm();
    if (f > 0) {
      const Eigen::VectorXd d2 = (posed_region(c.layer, u, c.motion.time(f)) - full.posed[f]).rowwise().squaredNorm();
      config.trajectory_sq += d2.sum();
      config.trajectory_max = std::max(config.trajectory_max, std::sqrt(d2.maxCoeff()));
    }
    if (config.invalid.empty()) {
      try {
        (void)model::energies(problem, state);
      } catch (const Error& e) {
        config.invalid = fmt::format("at t = {:.4f} s: {}", c.motion.time(f), e.what());
        logger()->warn("reduced {}: the full-space state leaves the material's range {}", name, config.invalid);
      }
    }
  };
  record(0);
  const model::StepStats total = model::run_frames(*built, c.frame_loop(), [&](int f, double, const model::StepStats&) {
    record(static_cast<std::size_t>(f));
    progress.advance();
  });
  config.cubature_tets = solver.cubature().size();
  config.seconds = total.seconds;
  config.elastic_seconds = total.elastic_seconds;
  config.inertia_seconds = total.inertia_seconds;
  config.solve_seconds = total.solve_seconds;
  config.newton = total.newton_iterations;
  config.retries = total.failed_attempts;
  config.frames = c.steps;
  config.sigma = amplitude.sigma();
}

/// The trade-off table, the per-vertex maps and summary.json's per-configuration records.
struct CompareReport {
  std::vector<compare::TradeoffRow> rows;  ///< the full space first
  vtk::Fields fields;                      ///< of compare.vtp, on the body's vertices
  std::vector<compare::ReducedTimings> timings;
  nlohmann::json reduced = nlohmann::json::array();
};

CompareReport make_report(const CompareCase& c, const FullReference& full,
                          const std::vector<std::unique_ptr<Configuration>>& configs) {
  CompareReport report;
  const std::vector<int>& region = c.layer.mesh->region_surface.vertices;
  compare::TradeoffRow full_row;
  full_row.seconds_per_frame = per_frame(full.total.seconds, c.steps);
  full_row.frames_per_second = full.total.seconds > 0 ? c.steps / full.total.seconds : 0.0;
  full_row.sigma_mean_mm = 1e3 * full.sigma.mean();
  full_row.recovered_fraction = 1.0;
  full_row.sigma_correlation = 1.0;
  report.rows.push_back(full_row);
  auto scatter = [&](const Eigen::VectorXd& region_values) {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(c.layer.shaped.rows(), 1);
    for (Eigen::Index r = 0; r < c.regions; ++r) out(region[static_cast<std::size_t>(r)], 0) = region_values[r];
    return out;
  };
  report.fields.point_data.push_back({"sigma_full", scatter(1e3 * full.sigma), false});
  report.fields.point_data.push_back({"soft_region", scatter(Eigen::VectorXd::Ones(c.regions)), true});
  report.fields.point_data.push_back(
      {"region", scatter(Eigen::VectorXd::Ones(c.regions)), true});  // soft_region's older name
  for (const auto& cp : configs) {
    const Configuration& config = *cp;
    compare::TradeoffRow row;
    row.reduced = true;
    row.handles = config.handles;
    row.cubature = config.cubature_request > 0 ? config.cubature_request : config.model.cubature.size();
    row.coordinates = config.model.subspace.num_dofs();
    row.seconds_per_frame = per_frame(config.seconds, config.frames);
    row.frames_per_second = config.seconds > 0 ? config.frames / config.seconds : 0.0;
    row.sigma_mean_mm = 1e3 * config.sigma.mean();
    row.recovered_fraction = full.sigma.mean() > 0 ? config.sigma.mean() / full.sigma.mean() : std::nan("");
    row.rms_error_mm = 1e3 * std::sqrt(config.error_sq.sum() / full.samples);
    row.relative_rms_error = full.rms > 0 ? std::sqrt(config.error_sq.sum() / full.samples) / full.rms : std::nan("");
    row.valid = config.invalid.empty();
    row.sigma_correlation = correlation(config.sigma, full.sigma);
    row.trajectory_rms_mm =
        1e3 * std::sqrt(config.trajectory_sq / (static_cast<double>(c.regions) * static_cast<double>(c.steps)));
    row.trajectory_max_mm = 1e3 * config.trajectory_max;
    report.rows.push_back(row);
    const std::string suffix = compare::config_suffix(row.handles, row.cubature);
    const Eigen::VectorXd rms_vertex = (config.error_sq / static_cast<double>(full.u.size())).cwiseSqrt();
    report.fields.point_data.push_back({"sigma_reduced_" + suffix, scatter(1e3 * config.sigma), false});
    report.fields.point_data.push_back({"sigma_error_" + suffix, scatter(1e3 * (config.sigma - full.sigma)), false});
    report.fields.point_data.push_back({"rms_error_" + suffix, scatter(1e3 * rms_vertex), false});
    const compare::ReducedTimings t{row.handles,
                                    row.cubature,
                                    per_frame(config.elastic_seconds, config.frames),
                                    per_frame(config.inertia_seconds, config.frames),
                                    per_frame(config.solve_seconds, config.frames),
                                    per_frame(static_cast<double>(config.newton), config.frames)};
    report.timings.push_back(t);
    const double speedup = row.seconds_per_frame > 0 ? full_row.seconds_per_frame / row.seconds_per_frame : 0.0;
    report.reduced.push_back(
        {{"handles", row.handles},
         {"bone_handles", config.model.handles.bone_joints().size()},
         {"coordinates", row.coordinates},
         {"cubature", row.cubature},
         {"cubature_tets", config.cubature_tets},
         {"cubature_method", config.model.cubature.method},
         {"cache", config.model.cache_outcome},
         {"fields", {"sigma_reduced_" + suffix, "sigma_error_" + suffix, "rms_error_" + suffix}},
         {"seconds_per_frame", row.seconds_per_frame},
         {"frames_per_second", row.frames_per_second},
         {"elastic_seconds_per_frame", t.elastic_seconds_per_frame},
         {"inertia_seconds_per_frame", t.inertia_seconds_per_frame},
         {"solve_seconds_per_frame", t.solve_seconds_per_frame},
         {"newton_iterations", config.newton},
         {"failed_attempts", config.retries},
         {"speedup", speedup},
         {"sigma_mean_mm", row.sigma_mean_mm},
         {"sigma_max_mm", 1e3 * config.sigma.maxCoeff()},
         {"recovered_fraction", row.recovered_fraction},
         {"rms_error_mm", row.rms_error_mm},
         {"max_vertex_rms_error_mm", 1e3 * rms_vertex.maxCoeff()},
         {"relative_rms_error", row.relative_rms_error},
         {"sigma_correlation", row.sigma_correlation},
         {"trajectory_rms_mm", row.trajectory_rms_mm},
         {"trajectory_max_mm", row.trajectory_max_mm},
         {"within_material_range", row.valid},
         {"out_of_range", config.invalid.empty() ? nlohmann::json(nullptr) : nlohmann::json(config.invalid)}});
    logger()->info(
        "reduced {} handles, {} cubature tets: {:.2f} ms per frame ({:.0f}× faster), {:.0f}% of the dynamics, relative "
        "RMS error {:.3f}",
        row.handles, row.cubature, 1e3 * row.seconds_per_frame, speedup, 100.0 * row.recovered_fraction,
        row.relative_rms_error);
  }
  return report;
}

/// summary.json of a comparison.
nlohmann::json compare_summary(const CompareCase& c, const FullReference& full, const CompareReport& report,
                               const Invocation& invocation, int size, const std::string& png) {
  const model::Problem& problem = c.layer.problem;
  const compare::TradeoffRow& full_row = report.rows.front();
  nlohmann::json summary = summary_header("compare", invocation.argc, invocation.argv);
  summary["body"] = body::body_label(c.opt.subject);
  summary["subject"] = c.subject_label;
  summary["beta"] = std::vector<double>(c.beta.data(), c.beta.data() + c.beta.size());
  summary["motion"] = {
      {"name", c.motion.name}, {"source", c.motion.source}, {"fps", c.motion.fps}, {"frames", c.motion.num_frames()}};
  summary["mesh"] = {{"mesher", c.opt.layer.mesher},
                     {"size", c.opt.mesh},
                     {"nodes", problem.num_nodes()},
                     {"tets", problem.num_tets()},
                     {"constrained_dofs", problem.dirichlet.dof.size()},
                     {"region_vertices", c.regions},
                     {"body_vertices", c.model.num_vertices()}};
  summary["material"] = material_summary(c.opt.layer, c.material_file);
  summary["step"] = c.h;
  summary["substeps"] = c.opt.substeps;
  summary["integrator"] = model::to_string(c.integrator);
  summary["mass"] = c.opt.layer.mass;
  summary["sweep"] = {{"handles", c.handle_sweep},
                      {"cubature", c.cubature_sweep},
                      {"cubature_weights", c.opt.reduced.cubature_weights},
                      {"affine", c.opt.reduced.affine}};
  summary["full"] = {{"processes", size},
                     {"free_dofs", problem.num_dofs() - static_cast<int>(problem.dirichlet.dof.size())},
                     {"seconds_per_frame", full_row.seconds_per_frame},
                     {"frames_per_second", full_row.frames_per_second},
                     {"newton_iterations", full.total.newton_iterations},
                     {"linear_iterations", full.total.linear_iterations},
                     {"failed_attempts", full.total.failed_attempts},
                     {"sigma_mean_mm", full_row.sigma_mean_mm},
                     {"sigma_max_mm", 1e3 * full.sigma.maxCoeff()},
                     {"displacement_rms_mm", 1e3 * full.rms}};
  summary["reduced"] = report.reduced;
  summary["output"] = {{"fields", "compare.vtp"},
                       {"table", "tradeoff.csv"},
                       {"markdown", "tradeoff.md"},
                       {"plot", png.empty() ? nlohmann::json(nullptr) : nlohmann::json(png)}};
  summary["units"] = {{"sigma", "mm"},
                      {"rms_error", "mm"},
                      {"trajectory_rms", "mm"},
                      {"trajectory_max", "mm"},
                      {"seconds_per_frame", "s"}};
  return summary;
}

/// Writes the run folder at once: compare.vtp, tradeoff.csv / .md / .png and summary.json.
void write_compare_folder(const CompareCase& c, const FullReference& full, const CompareReport& report,
                          const Invocation& invocation, int size, nlohmann::json timings, double total_seconds) {
  RunFolder run(c.opt.out);
  vtk::write_surface(run.stage("compare.vtp"), c.layer.shaped, c.model.faces, report.fields);
  compare::write_tradeoff_csv(run.stage("tradeoff.csv"), report.rows);
  const std::string title = fmt::format("{} · {} · {} mesh · {} frames at {:g} fps", c.subject_label, c.motion.name,
                                        c.opt.mesh, c.motion.num_frames(), c.motion.fps);
  compare::write_tradeoff_markdown(
      run.stage("tradeoff.md"), "Full space against reduced models: " + title,
      {fmt::format("layer: {} nodes, {} tets, {} region vertices; step {:.4g} s", c.layer.problem.num_nodes(),
                   c.layer.problem.num_tets(), c.regions, c.h),
       fmt::format("full space: {} Newton and {} linear iterations on {} process(es)", full.total.newton_iterations,
                   full.total.linear_iterations, size),
       "σ: dynamics amplitude per vertex (docs/physics.md §4), mean over the region; recovered = mean σ / mean σ of "
       "the full space",
       "RMS error: of |u − u_full| over region vertices and frames; relative: divided by the RMS of u_full",
       "σ correlation: Pearson correlation of σ and σ_full over the region's vertices; trajectory RMS / max: of |p − "
       "p_full| over "
       "region vertices and frames 1..F, p the posed body surface that `sflsh simulate` writes"},
      report.rows, report.timings);
  std::string png = "tradeoff.png";
  try {
    compare::write_tradeoff_png(run.stage("tradeoff.png"), "Error against time: " + title, report.rows);
  } catch (const Error& e) {  // the picture is a convenience: the tables never depend on a display
    logger()->warn("skipped tradeoff.png: {}", e.what());
    png.clear();
  }
  nlohmann::json summary = compare_summary(c, full, report, invocation, size, png);
  summary["timings"] = std::move(timings);
  write_summary(run, summary, total_seconds);
  run.commit();
}

void run_compare(const CompareOptions& opt, const Invocation& invocation, int rank, int size) {
  const auto t_start = Clock::now();
  CompareCase c(opt);
  prepare_case(c);
  const auto t_models = Clock::now();
  const std::vector<std::unique_ptr<Configuration>> configs = build_configurations(c, rank);
  const double models_seconds = seconds_since(t_models);
  logger()->info(
      "compare: {} nodes, {} tets, {} region vertices, {} frames at {} fps; reference on {} process(es), {} reduced "
      "configuration(s)",
      c.layer.problem.num_nodes(), c.layer.problem.num_tets(), c.regions, c.motion.num_frames(), c.motion.fps, size,
      c.handle_sweep.size() * c.cubature_sweep.size());
  const FullReference full = run_full_reference(c, rank);
  logger()->info("full space: {:.3f} s per frame, mean σ = {:.3f} mm", per_frame(full.total.seconds, c.steps),
                 1e3 * full.sigma.mean());
  if (rank != 0) return;
  Progress progress("reduced frames", configs.size() * static_cast<std::size_t>(c.steps));
  for (const auto& config : configs) run_configuration(*config, c, full, progress);
  progress.finish();
  const CompareReport report = make_report(c, full, configs);
  // Everything is computed: the run folder appears at once.
  write_compare_folder(c, full, report, invocation, size,
                       {{"build_seconds", c.build_seconds}, {"models_seconds", models_seconds}},
                       seconds_since(t_start));
  logger()->info("compare: wrote {} ({} configurations, {:.1f} s)", opt.out, configs.size(), seconds_since(t_start));
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
  add_frame_options(*cmd, opt->frames, opt->fps, opt->substeps);
  add_integrator_option(*cmd, opt->integrator);
  add_mass_option(*cmd, opt->layer);
  add_mesh_option(*cmd, opt->mesh);
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
