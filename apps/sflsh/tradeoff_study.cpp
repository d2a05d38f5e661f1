// sflsh tradeoff's study: what accuracy costs in time. One case (subject, motion, material) is run by a hierarchy of
// models — a reference, the full-space solver on several meshes, integrators, masses and steps, reduced models
// with several handle and cubature counts, integrators, masses and steps — and each is scored against the
// reference on the same posed body-surface points at the same frame times (docs/tradeoff.md says exactly what is
// measured):
// RMS error [mm], relative error, σ ratio, solve seconds per frame, setup seconds. Writes tradeoff.csv/.md/.png
// and summary.json with the Pareto front and the cheapest configuration within an error budget.
#include "tradeoff_study.hpp"

#include "tradeoff_table.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/run/body_solver_factory.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>

namespace sflsh::app {

namespace {

using model::RowMatrixX3d;

void check_options(const TradeoffOptions& o) {
  require(o.fps > 0.0, "--fps must be positive, got {}", o.fps);
  require(o.frames >= 2, "--frames must be at least 2, got {}", o.frames);
  require(
      o.reference == "sundials" || o.reference == "backward_euler" || o.reference == "bdf2" || o.reference == "newmark",
      "--reference {}: expected sundials, backward_euler, bdf2 or newmark", o.reference);
  for (const std::string& c : o.reference_checks)
    require(c == "time" || c == "space", "--reference-check {}: expected time and/or space", c);
  require(o.reference_check_frames >= 2, "--reference-check-frames must be at least 2, got {}",
          o.reference_check_frames);
  require(!o.integrators.empty() && !o.masses.empty(), "--integrators and --masses need at least one entry each");
  require(o.rtol > 0.0 && o.atol > 0.0, "--rtol and --atol must be positive, got {} and {}", o.rtol, o.atol);
  require(o.budget_mm >= 0.0 && o.budget_relative >= 0.0,
          "--budget-mm and --budget-relative must be positive, got {} and {}", o.budget_mm, o.budget_relative);
  for (const auto* list : {&o.substeps, &o.reduced_substeps})
    for (int s : *list)
      require(s >= 1 && s <= 1'000'000, "--substeps and --reduced-substeps: {} is outside [1, 10⁶]", s);
  for (int h : o.handles) require(h >= 1 && h <= 1'000'000, "--handles: {} is outside [1, 10⁶]", h);
  for (int k : o.cubature) require(k >= 0, "--cubature: {} is negative (0 = every tet)", k);
  if (o.reference != "sundials") {
    int finest = 0;
    for (int s : o.substeps) finest = std::max(finest, s);
    for (int s : o.reduced_substeps) finest = std::max(finest, s);
    require(o.reference_substeps > finest,
            "--reference-substeps {}: the stepping reference must take a smaller step than every tested model (more "
            "than {} substeps)",
            o.reference_substeps, finest);
  }
  check_layer_settings(o.layer);
}

/// The region's rows of a body-surface array.
RowMatrixX3d region_rows(const RowMatrixX3d& all, const std::vector<int>& region) {
  RowMatrixX3d out(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r) out.row(static_cast<Eigen::Index>(r)) = all.row(region[r]);
  return out;
}

/// The reference's posed region surface per frame and the size of its soft-tissue motion.
struct ReferenceTrack {
  std::vector<RowMatrixX3d> posed;  ///< frames 0..F, R×3 [m]
  double soft_rms = 0.0;            ///< RMS over region vertices and frames 1..F of posed − skinned [m]
  double sigma_mean = 0.0;          ///< mean σ over the region [m]
};

/// What one run measured.
struct Measured {
  double solve_seconds = 0.0;
  double error_sq = 0.0;    ///< Σ over frames 1..F and region vertices of |p − p_ref|² [m²]
  double sigma_mean = 0.0;  ///< [m]
  std::string invalid;      ///< why a reduced state left the material's range, or why the run failed
};

/// Runs one solver through the frame loop (model/frame_loop.hpp) over `frames` frames of `substeps` steps each,
/// summing the solve time. With `keep` the posed region surface is stored (the reference), with `ref` the error
/// against it is summed. σ is that of simulate's summary: of the unposed skin displacement u
/// (model::SimulationWriter), over frames 0..F.
Measured track(const model::BodyLayer& layer, const body::Motion& motion, std::size_t frames, model::BodySolver& solver,
               int substeps, bool check_range, ReferenceTrack* keep, const ReferenceTrack* ref) {
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  model::DynamicsAmplitude amplitude(region_normals(layer));
  Measured m;
  double soft_sq = 0.0;
  auto record = [&](std::size_t f) {
    const double t = motion.time(f);
    const model::State state = solver.current_state();
    require(state.x.allFinite(), "tradeoff: the state at t = {} is not finite", t);
    const RowMatrixX3d u = layer.surface_displacement(state.x);
    amplitude.add(u);
    const RowMatrixX3d posed = region_rows(layer.posed_surface_from_displacement(u, t), region);
    if (ref && f > 0) m.error_sq += (posed - ref->posed[f]).squaredNorm();
    if (keep) {
      const RowMatrixX3d skinned =
          region_rows(layer.posed_surface_from_displacement(RowMatrixX3d::Zero(u.rows(), 3), t), region);
      if (f > 0) soft_sq += (posed - skinned).squaredNorm();
      keep->posed.push_back(posed);
    }
    if (check_range && m.invalid.empty()) {
      try {
        (void)model::energies(layer.problem, state);
      } catch (const Error& e) {
        m.invalid = fmt::format("at t = {:.4f} s: {}", t, e.what());
      }
    }
  };
  record(0);
  model::FrameLoopOptions loop;
  loop.frames = static_cast<int>(frames);
  loop.fps = motion.fps;
  loop.substeps = substeps;
  m.solve_seconds = model::run_frames(solver, loop, [&](int f, double, const model::StepStats&) {
                      record(static_cast<std::size_t>(f));
                    }).seconds;
  m.sigma_mean = amplitude.sigma().mean();
  if (keep) {
    keep->soft_rms = std::sqrt(soft_sq / (static_cast<double>(region.size()) * static_cast<double>(frames - 1)));
    keep->sigma_mean = m.sigma_mean;
  }
  return m;
}

struct BuiltLayer {
  model::BodyLayer layer;
  double seconds = 0.0;
};

/// A copy of `problem` with inertia `mass` ("lumped" | "consistent"; `option` names the flag in errors): each run
/// gets its own, so that no run changes the layer another run uses.
model::Problem with_mass(const model::Problem& problem, const std::string& mass, const char* option) {
  model::Problem copy = problem;
  copy.mass_kind = model::parse_mass_kind(mass, option);
  return copy;
}

/// One tradeoff study: the case, its layers (every mesh asked for), the reference track and the scored rows.
/// Not movable: the layers refer to the body model.
class TradeoffStudy {
 public:
  explicit TradeoffStudy(const TradeoffOptions& opt) : opt_(opt) {}
  TradeoffStudy(const TradeoffStudy&) = delete;
  TradeoffStudy& operator=(const TradeoffStudy&) = delete;

  /// Loads the case and builds every layer, checking every handle count on it, before any solve (one message, no
  /// output).
  void prepare();
  /// The reference row and its track; `reference_json_` describes it.
  void run_reference();
  /// How converged the reference is: the same configuration at twice the substeps ("time") or on the next finer mesh
  /// ("space"), over the first frames, against the reference itself.
  void run_reference_checks();
  void run_full_rows();
  void run_reduced_rows();
  /// The Pareto front, the recommendation and the run folder (written at once).
  void write(const Invocation& invocation, double started_seconds_ago);

 private:
  BuiltLayer& layer_of(const std::string& mesh);
  /// One stepping run of the full-space solver (an integrator, a mass, substeps per frame) over the first `frames`
  /// frames.
  Measured run_full(const model::BodyLayer& layer, const std::string& integrator, const std::string& mass, int substeps,
                    std::size_t frames, ReferenceTrack* keep, const ReferenceTrack* against,
                    double& setup_seconds) const;
  Measured run_sundials_reference(const model::BodyLayer& layer, tradeoff::Row& row);
  /// Scores one run against the reference into its row; a solver that gives up is a row that failed, not a failed
  /// command.
  void add_row(tradeoff::Row row, const std::function<Measured()>& run);
  std::string reference_text() const;
  nlohmann::json rows_json() const;

  const TradeoffOptions& opt_;
  body::BodyModel model_;
  std::string subject_label_;
  body::Betas beta_;
  body::Motion motion_;
  std::optional<material::MaterialFile> material_file_;
  int steps_ = 0;
  std::map<std::string, BuiltLayer> layers_;  // std::map: references stay valid
  std::vector<int> region_;
  ReferenceTrack ref_;
  nlohmann::json reference_json_;
  std::vector<tradeoff::Row> rows_;
};

BuiltLayer& TradeoffStudy::layer_of(const std::string& mesh) {
  auto it = layers_.find(mesh);
  if (it != layers_.end()) return it->second;
  const auto t0 = Clock::now();
  model::BodyLayer l = model::build_body_layer(model_, beta_, motion_, material_file_ ? &*material_file_ : nullptr,
                                               opt_.layer.control_points, body_layer_options(opt_.layer, mesh));
  return layers_.emplace(mesh, BuiltLayer{std::move(l), seconds_since(t0)}).first->second;
}

void TradeoffStudy::prepare() {
  check_options(opt_);
  model_ = load_selected_body(opt_.subject);
  beta_ = selected_betas(opt_.subject, subject_label_);
  motion_ = body::load_motion(opt_.motion, opt_.fps, opt_.frames);
  motion_.validate();
  require(motion_.num_frames() >= 2, "tradeoff: the motion has {} frame(s); at least 2 are needed",
          motion_.num_frames());
  material_file_ = load_layer_material(opt_.layer);
  steps_ = static_cast<int>(motion_.num_frames()) - 1;
  (void)layer_of(opt_.reference_mesh);
  for (const std::string& c : opt_.reference_checks)
    if (c == "space" && opt_.reference_mesh != "fine")
      (void)layer_of(opt_.reference_mesh == "coarse" ? "default" : "fine");
  for (const std::string& mesh : opt_.meshes) (void)layer_of(mesh);
  for (const std::string& mesh : opt_.reduced_meshes) check_handle_counts(layer_of(mesh).layer, opt_.handles);
  region_ = layers_.at(opt_.reference_mesh).layer.mesh->region_surface.vertices;
  for (const auto& [mesh, built] : layers_)
    require(built.layer.mesh->region_surface.vertices == region_,
            "tradeoff: the {} mesh has a different skin region than the {} mesh", mesh, opt_.reference_mesh);
  logger()->info("tradeoff: {} frames at {:g} fps, {} region vertices; reference {} on the {} mesh",
                 motion_.num_frames(), motion_.fps, region_.size(), opt_.reference, opt_.reference_mesh);
}

Measured TradeoffStudy::run_full(const model::BodyLayer& layer, const std::string& integrator, const std::string& mass,
                                 int substeps, std::size_t frames, ReferenceTrack* keep, const ReferenceTrack* against,
                                 double& setup_seconds) const {
  const model::Problem problem = with_mass(layer.problem, mass, "--masses");
  run::SolverChoice choice;
  choice.integrator = model::parse_integrator(integrator, "--integrators");
  const auto t0 = Clock::now();
  const model::State initial = model::initial_state(problem, 0.0);
  const run::BuiltSolver solver = run::make_body_solver(problem, choice, initial);
  setup_seconds = seconds_since(t0);
  return track(layer, motion_, frames, *solver, substeps, false, keep, against);
}

Measured TradeoffStudy::run_sundials_reference(const model::BodyLayer& layer, tradeoff::Row& row) {
  const model::Problem problem = with_mass(layer.problem, opt_.reference_mass, "--reference-mass");
  const auto t0 = Clock::now();
  const model::State initial = model::initial_state(problem, 0.0);
  run::SolverChoice choice;
  choice.kind = run::SolverKind::sundials;
  choice.sundials.rtol = opt_.rtol;
  choice.sundials.atol = opt_.atol;
  choice.step_rate = motion_.fps;  // steps end at the frame times f / fps exactly
  const run::BuiltSolver solver = run::make_body_solver(problem, choice, initial);
  row.setup_seconds = layers_.at(opt_.reference_mesh).seconds + seconds_since(t0);
  const Measured m = track(layer, motion_, motion_.num_frames(), *solver, 1, false, &ref_, nullptr);
  const fullspace::ReferenceStats& st = solver.sundials->stats();
  const fullspace::ReferenceOptions& ro = solver.sundials->options();
  reference_json_ = {{"integrator", "sundials"},
                     {"method", "ARKODE ARKStep, adaptive implicit SDIRK, KLU"},
                     {"rtol", opt_.rtol},
                     {"atol", opt_.atol},
                     {"order", ro.order},
                     {"internal_steps", st.steps},
                     {"error_test_fails", st.error_test_fails},
                     {"newton_iterations", st.nonlin_iters},
                     {"mean_step", motion_.duration() / std::max(1L, st.steps)}};
  return m;
}

void TradeoffStudy::run_reference() {
  const BuiltLayer& built = layers_.at(opt_.reference_mesh);
  tradeoff::Row row{"reference", opt_.reference, opt_.reference_mesh};
  row.mass = opt_.reference_mass;
  Measured m;
  if (opt_.reference == "sundials") {
    m = run_sundials_reference(built.layer, row);
  } else {
    row.substeps = opt_.reference_substeps;
    row.step = 1.0 / (motion_.fps * opt_.reference_substeps);
    double setup = 0.0;
    m = run_full(built.layer, opt_.reference, opt_.reference_mass, row.substeps, motion_.num_frames(), &ref_, nullptr,
                 setup);
    row.setup_seconds = built.seconds + setup;
    reference_json_ = {{"integrator", opt_.reference}, {"substeps", row.substeps}, {"step", row.step}};
  }
  row.seconds_per_frame = m.solve_seconds / steps_;
  row.sigma_ratio = 1.0;
  rows_.push_back(row);
  reference_json_["mass"] = opt_.reference_mass;
  reference_json_["mesh"] = opt_.reference_mesh;
  reference_json_["nodes"] = built.layer.problem.num_nodes();
  reference_json_["tets"] = built.layer.problem.num_tets();
  reference_json_["preset"] = opt_.preset;
  reference_json_["seconds_per_frame"] = row.seconds_per_frame;
  reference_json_["soft_tissue_rms_mm"] = 1e3 * ref_.soft_rms;
  reference_json_["sigma_mean_mm"] = 1e3 * ref_.sigma_mean;
  logger()->info("reference: {:.3f} s per frame, soft-tissue RMS {:.3f} mm, mean σ {:.3f} mm", row.seconds_per_frame,
                 1e3 * ref_.soft_rms, 1e3 * ref_.sigma_mean);
  require(ref_.soft_rms > 0.0, "tradeoff: the reference does not move the soft tissue (motion {}, {} frames)",
          motion_.name, motion_.num_frames());
}

void TradeoffStudy::run_reference_checks() {
  nlohmann::json checks = nlohmann::json::array();
  for (const std::string& check : opt_.reference_checks) {
    require(opt_.reference != "sundials",
            "--reference-check applies to a stepping reference, not sundials (its error is controlled)");
    const std::size_t frames =
        std::min<std::size_t>(motion_.num_frames(), static_cast<std::size_t>(opt_.reference_check_frames));
    const std::string mesh =
        check == "space" ? (opt_.reference_mesh == "coarse" ? "default" : "fine") : opt_.reference_mesh;
    require(check == "time" || opt_.reference_mesh != "fine",
            "--reference-check space: there is no mesh finer than fine");
    const BuiltLayer& built = layer_of(mesh);
    require(built.layer.mesh->region_surface.vertices == region_, "tradeoff: the {} mesh has a different skin region",
            mesh);
    const int substeps = check == "time" ? 2 * opt_.reference_substeps : opt_.reference_substeps;
    double setup = 0.0;
    const Measured m =
        run_full(built.layer, opt_.reference, opt_.reference_mass, substeps, frames, nullptr, &ref_, setup);
    const double rms = std::sqrt(m.error_sq / (static_cast<double>(region_.size()) * static_cast<double>(frames - 1)));
    checks.push_back({{"check", check},
                      {"mesh", mesh},
                      {"substeps", substeps},
                      {"frames", frames},
                      {"rms_difference_mm", 1e3 * rms},
                      {"relative_difference", rms / ref_.soft_rms},
                      {"seconds", m.solve_seconds}});
    logger()->info(
        "reference check ({}): {} mesh, {} substeps, {} frames: RMS difference {:.4f} mm ({:.2f} % of the soft-tissue "
        "motion)",
        check, mesh, substeps, frames, 1e3 * rms, 100.0 * rms / ref_.soft_rms);
  }
  reference_json_["checks"] = checks;
}

void TradeoffStudy::add_row(tradeoff::Row row, const std::function<Measured()>& run) {
  try {
    const Measured m = run();
    const double samples = static_cast<double>(region_.size()) * steps_;
    row.seconds_per_frame = m.solve_seconds / steps_;
    row.rms_error_mm = 1e3 * std::sqrt(m.error_sq / samples);
    row.relative_error = std::sqrt(m.error_sq / samples) / ref_.soft_rms;
    row.sigma_ratio = ref_.sigma_mean > 0 ? m.sigma_mean / ref_.sigma_mean : std::nan("");
    row.valid = m.invalid.empty();
    if (!row.valid) logger()->warn("{}: {}", row.label(), m.invalid);
    logger()->info("{}: {:.4f} s per frame, RMS error {:.4f} mm (relative {:.3f}), σ ratio {:.3f}", row.label(),
                   row.seconds_per_frame, row.rms_error_mm, row.relative_error, row.sigma_ratio);
  } catch (const Error& e) {
    row.valid = false;
    row.rms_error_mm = row.relative_error = row.sigma_ratio = std::nan("");
    logger()->warn("{} failed: {}", row.label(), e.what());
  }
  rows_.push_back(row);
}

void TradeoffStudy::run_full_rows() {
  for (const std::string& mesh : opt_.meshes) {
    const BuiltLayer& built = layers_.at(mesh);
    for (const std::string& integrator : opt_.integrators)
      for (const std::string& mass : opt_.masses)
        for (int substeps : opt_.substeps) {
          tradeoff::Row row{"full", integrator, mesh};
          row.mass = mass;
          row.substeps = substeps;
          row.step = 1.0 / (motion_.fps * substeps);
          double setup_seconds = 0.0;  // stays 0 for a run that failed
          add_row(row, [&] {
            double setup = 0.0;
            const Measured m =
                run_full(built.layer, integrator, mass, substeps, motion_.num_frames(), nullptr, &ref_, setup);
            setup_seconds = built.seconds + setup;
            return m;
          });
          rows_.back().setup_seconds = setup_seconds;
        }
  }
}

void TradeoffStudy::run_reduced_rows() {
  for (const std::string& mesh : opt_.reduced_meshes) {
    const BuiltLayer& built = layers_.at(mesh);
    for (int handles : opt_.handles)
      for (int k : opt_.cubature) {
        const auto t0 = Clock::now();
        run::SolverChoice reduced_choice;
        reduced_choice.kind = run::SolverKind::reduced;
        reduced_choice.handles = handles;
        reduced_choice.cubature = k;
        reduced_choice.reduced_settings = opt_.reduced;
        const reduced::ReducedModel reduced_model =
            run::make_reduced_model(built.layer, reduced_choice, opt_.layer.cache);
        const double model_seconds = seconds_since(t0);
        for (const std::string& integrator : opt_.integrators)
          for (const std::string& mass : opt_.masses)
            for (int substeps : opt_.reduced_substeps) {
              tradeoff::Row row{"reduced",
                                integrator,
                                mesh,
                                handles,
                                static_cast<int>(reduced_model.cubature.size()),
                                substeps,
                                1.0 / (motion_.fps * substeps)};
              row.mass = mass;
              double setup_seconds = 0.0;  // stays 0 for a run that failed in its set-up
              add_row(row, [&] {
                const model::Problem problem = with_mass(built.layer.problem, mass, "--masses");
                run::SolverChoice choice = reduced_choice;
                choice.integrator = model::parse_integrator(integrator, "--integrators");
                const auto t1 = Clock::now();
                const model::State initial = model::initial_state(problem, 0.0);
                const run::BuiltSolver solver =
                    run::make_body_solver(problem, choice, initial, run::parts_of(reduced_model));
                setup_seconds = built.seconds + model_seconds + seconds_since(t1);
                return track(built.layer, motion_, motion_.num_frames(), *solver, substeps, true, nullptr, &ref_);
              });
              rows_.back().setup_seconds = setup_seconds;
            }
      }
  }
}

std::string TradeoffStudy::reference_text() const {
  return opt_.reference == "sundials"
             ? fmt::format("SUNDIALS ARKODE (adaptive, rtol {:g}, atol {:g}) on the {} mesh", opt_.rtol, opt_.atol,
                           opt_.reference_mesh)
             : fmt::format("{} with {} masses at {} substeps per frame on the {} mesh", opt_.reference,
                           opt_.reference_mass, opt_.reference_substeps, opt_.reference_mesh);
}

nlohmann::json TradeoffStudy::rows_json() const {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json out = nlohmann::json::array();
  for (const tradeoff::Row& r : rows_)
    out.push_back({{"label", r.label()},
                   {"model", r.model},
                   {"integrator", r.integrator},
                   {"mass", r.mass},
                   {"mesh", r.mesh},
                   {"handles", r.handles},
                   {"cubature", r.cubature},
                   {"substeps", r.substeps},
                   {"step", r.step},
                   {"setup_seconds", r.setup_seconds},
                   {"seconds_per_frame", r.seconds_per_frame},
                   {"rms_error_mm", number(r.rms_error_mm)},
                   {"relative_error", number(r.relative_error)},
                   {"sigma_ratio", number(r.sigma_ratio)},
                   {"valid", r.valid},
                   {"pareto", r.pareto}});
  return out;
}

void TradeoffStudy::write(const Invocation& invocation, double started_seconds_ago) {
  const tradeoff::Budget budget{opt_.budget_mm > 0 ? std::optional<double>(opt_.budget_mm) : std::nullopt,
                                opt_.budget_relative > 0 ? std::optional<double>(opt_.budget_relative) : std::nullopt};
  tradeoff::mark_pareto_front(rows_);
  const std::optional<std::size_t> pick = tradeoff::recommend(rows_, budget);
  const std::string recommendation = tradeoff::recommendation_text(rows_, budget, pick);
  logger()->info("{}", recommendation);

  RunFolder run(opt_.out);
  tradeoff::write_csv(run.stage("tradeoff.csv"), rows_);
  const std::string title =
      fmt::format("{} · {} · {} frames at {:g} fps", subject_label_, motion_.name, motion_.num_frames(), motion_.fps);
  const std::string reference = reference_text();
  tradeoff::write_markdown(
      run.stage("tradeoff.md"), "What accuracy costs in time: " + title,
      {fmt::format("preset {}; reference: {}", opt_.preset, reference),
       fmt::format("error: RMS over the {} region vertices of the body surface and frames 1..{} of |p − p_ref|, p the "
                   "posed body "
                   "surface every model writes (model::BodyLayer::posed_surface); relative: divided by the RMS of the "
                   "reference's "
                   "soft-tissue displacement p_ref − p_skinned ({:.3f} mm)",
                   region_.size(), steps_, 1e3 * ref_.soft_rms),
       fmt::format("σ ratio: mean σ / mean σ_ref over the region (model::DynamicsAmplitude of the unposed skin "
                   "displacement, as "
                   "`sflsh simulate` reports it; σ_ref = {:.3f} mm)",
                   1e3 * ref_.sigma_mean),
       "s/frame: solve time per output frame (steps only); setup: layer build + solver (+ reduced model) setup",
       "Pareto: no other valid row is both faster and more accurate"},
      rows_, recommendation);
  std::string png = "tradeoff.png";
  try {
    tradeoff::write_png(run.stage("tradeoff.png"), "Error against time: " + title, rows_);
  } catch (const Error& e) {  // the picture is a convenience: the tables never depend on a display
    logger()->warn("skipped tradeoff.png: {}", e.what());
    png.clear();
  }
  const nlohmann::json row_json = rows_json();
  nlohmann::json summary = summary_header("tradeoff", invocation.argc, invocation.argv);
  summary["preset"] = opt_.preset;
  summary["body"] = body::body_label(opt_.subject);
  summary["subject"] = subject_label_;
  summary["beta"] = std::vector<double>(beta_.data(), beta_.data() + beta_.size());
  summary["motion"] = {
      {"name", motion_.name}, {"source", motion_.source}, {"fps", motion_.fps}, {"frames", motion_.num_frames()}};
  summary["material"] = material_summary(opt_.layer, material_file_);
  summary["region_vertices"] = region_.size();
  summary["reference"] = reference_json_;
  summary["reference"]["description"] = reference;
  summary["rows"] = row_json;
  summary["budget"] = {
      {"rms_error_mm", budget.mm ? nlohmann::json(*budget.mm) : nlohmann::json(nullptr)},
      {"relative_error", budget.relative ? nlohmann::json(*budget.relative) : nlohmann::json(nullptr)}};
  summary["recommendation"] = {{"row", pick ? nlohmann::json(*pick) : nlohmann::json(nullptr)},
                               {"configuration", pick ? row_json[*pick] : nlohmann::json(nullptr)},
                               {"message", recommendation}};
  summary["output"] = {{"table", "tradeoff.csv"},
                       {"markdown", "tradeoff.md"},
                       {"plot", png.empty() ? nlohmann::json(nullptr) : nlohmann::json(png)}};
  summary["units"] = {{"rms_error", "mm"}, {"seconds_per_frame", "s"}, {"setup_seconds", "s"}, {"step", "s"}};
  write_summary(run, summary, started_seconds_ago);
  run.commit();
  logger()->info("tradeoff: wrote {} ({} rows, {:.1f} s)", run.dir().string(), rows_.size(), started_seconds_ago);
}

}  // namespace

void run_tradeoff(const TradeoffOptions& opt, const Invocation& invocation, int rank, int size) {
  const auto t_start = Clock::now();
  require(size == 1, "tradeoff runs on one process (got {}): its timings compare solvers on the same cores", size);
  (void)rank;
  TradeoffStudy study(opt);
  study.prepare();
  study.run_reference();
  study.run_reference_checks();
  study.run_full_rows();
  study.run_reduced_rows();
  // Everything is computed: the run folder appears at once.
  study.write(invocation, seconds_since(t_start));
}

}  // namespace sflsh::app
