// sflsh sweep: a robustness sweep over subjects × motions × meshes. Every case runs in-process exactly as
// `sflsh simulate --solver … --no-output` would (run_body_simulation), its error is caught and recorded, and the
// report (sweep.csv, sweep.md, summary.json) is written whether or not cases failed; the exit code says whether
// any did.
#include "commands.hpp"
#include "simulate_run.hpp"
#include "sweep_report.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

namespace sflsh::app {

namespace {

constexpr const char* kDefaultSubjects = "table1,OPEN_TRAIN_1,OPEN_TEST_3";
constexpr const char* kDefaultMotions = "one_leg_jump,running_on_spot,shake_hips,jiggle_on_toes,shake_shoulders,dance";

struct SweepOptions {
  BodyRunSettings base;  ///< solver, frames, fps, integrator, layer, reduced model (subject, motion, mesh per case)
  std::string meshes = "coarse";
  std::string subjects = kDefaultSubjects;
  std::string motions = kDefaultMotions;
  int threads = 0;
  std::string out;
};

/// The trimmed, non-empty items of a comma-separated list.
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    if (first != std::string::npos) items.push_back(item.substr(first, last - first + 1));
  }
  return items;
}

void add_unique(std::vector<std::string>& list, const std::string& value) {
  if (std::find(list.begin(), list.end(), value) == list.end()) list.push_back(value);
}

/// Subject names of --subjects: names, `table1` (the paper's DYNA_1–5, TEST_1–5), `open` (every OPEN_*), `all`.
std::vector<std::string> expand_subjects(const std::string& text) {
  const std::vector<body::Subject> known = body::default_subjects();
  std::vector<std::string> names;
  for (const std::string& item : split_list(text)) {
    if (item == "table1" || item == "open" || item == "all") {
      for (const body::Subject& s : known)
        if (item == "all" || (item == "table1" && s.body == "smpl") || (item == "open" && s.body == "open"))
          add_unique(names, s.name);
    } else {
      add_unique(names, body::find_subject(known, item).name);  // throws, listing the known names
    }
  }
  require(!names.empty(), "--subjects {}: no subject (expected names, table1, open or all)", text);
  return names;
}

/// Motion names of --motions: procedural or showcase names, AMASS paths, or `all` (every procedural and showcase
/// motion).
std::vector<std::string> expand_motions(const std::string& text, double fps) {
  std::vector<std::string> names;
  for (const std::string& item : split_list(text)) {
    if (item == "all") {
      for (const std::string& m : body::procedural_motion_names()) add_unique(names, m);
      for (const std::string& m : body::showcase_motion_names()) add_unique(names, m);
    } else {
      (void)body::load_motion(item, fps, 2);  // an unknown name or unreadable file fails here, before any run
      add_unique(names, item);
    }
  }
  require(!names.empty(), "--motions {}: no motion (expected names or all)", text);
  return names;
}

std::vector<std::string> expand_meshes(const std::string& text) {
  std::vector<std::string> meshes;
  for (const std::string& item : split_list(text)) {
    require(item == "coarse" || item == "default" || item == "fine", "--mesh {}: '{}' is not coarse, default or fine",
            text, item);
    add_unique(meshes, item);
  }
  require(!meshes.empty(), "--mesh {}: no mesh (expected coarse, default and/or fine)", text);
  return meshes;
}

/// One case, run as `sflsh simulate --no-output` would; its error is caught into the row.
void run_case(const SweepOptions& opt, sweep::SweepRun& run) {
  BodyRunSettings settings = opt.base;
  settings.mesh = run.mesh;
  settings.subject.subject = run.subject;
  settings.motion = run.motion;
  BodyRunReporting reporting;
  reporting.progress = false;
  reporting.log_details = false;
  reporting.on_frame = [&run](int frame) { run.frames = frame + 1; };
  reporting.on_setup = [&run](const nlohmann::json& setup) {
    run.frames = 1;  // the rest state
    run.tets = setup["tets"].get<int>();
    run.coordinates = setup["coordinates"].get<int>();
    run.cubature_tets = setup["cubature"].get<int>();
  };
  const auto t0 = Clock::now();
  try {
    const nlohmann::json s = run_body_simulation(settings, nullptr, 0, 1, reporting);
    const nlohmann::json& timings = s["timings"];
    const long steps = std::max(1L, s["motion"]["frames"].get<long>() - 1);
    run.ok = true;
    run.frames = s["motion"]["frames"].get<int>();
    run.sigma_mm = s["dynamics"].value("sigma_mean_mm", 0.0);
    run.sigma_max_mm = s["dynamics"].value("sigma_max_mm", 0.0);
    run.newton_per_frame = s["solver"]["newton_iterations"].get<double>() / static_cast<double>(steps);
    run.solve_seconds = timings["solve_seconds"].get<double>();
    run.fps = timings["frames_per_second"].get<double>();
    run.failed_attempts = s["solver"]["failed_attempts"].get<long>();
    run.tets = s["mesh"]["tets"].get<int>();
    if (s.contains("reduced")) {
      run.coordinates = s["reduced"]["coordinates"].get<int>();
      run.cubature_tets = s["reduced"]["cubature"].get<int>();
      run.factorizations = s["reduced"]["factorizations"].get<long>();
    }
  } catch (const std::exception& e) {
    run.ok = false;
    run.error = sweep::one_line(e.what());
    if (run.error.empty()) run.error = "unknown error";
  }
  run.seconds = seconds_since(t0);
}

/// What a sweep runs: meshes × subjects × motions, in that nesting order (the cases of one mesh together).
struct SweepPlan {
  std::vector<std::string> meshes, subjects, motions;
  std::vector<sweep::SweepRun> runs;
  int threads = 1;  ///< cases at once (full space: one, PETSc objects are not shared across threads)

  std::size_t per_mesh() const { return subjects.size() * motions.size(); }
};

SweepPlan plan_sweep(const SweepOptions& opt) {
  SweepPlan plan;
  plan.meshes = expand_meshes(opt.meshes);
  plan.subjects = expand_subjects(opt.subjects);
  plan.motions = expand_motions(opt.motions, opt.base.fps);
  for (const std::string& mesh : plan.meshes)
    for (const std::string& subject : plan.subjects)
      for (const std::string& motion : plan.motions) {
        sweep::SweepRun r;
        r.mesh = mesh;
        r.subject = subject;
        r.motion = motion;
        r.frames_requested = opt.base.frames;
        plan.runs.push_back(r);
      }
  plan.threads =
      opt.base.solver == "full" ? 1 : (opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency());
  return plan;
}

/// Runs every case, one info line each (failures too: the report lists them, and with -q only the final line
/// remains). The first case of a mesh runs alone: it builds (or loads) the template mesh and the reduced model that
/// every other case of that mesh then reads from the cache.
void run_cases(const SweepOptions& opt, SweepPlan& plan) {
  std::atomic<int> done{0};
  auto run_one = [&](std::size_t i) {
    sweep::SweepRun& r = plan.runs[i];
    run_case(opt, r);
    const int k = ++done;
    if (r.ok)
      logger()->info("sweep [{}/{}] {} {} {}: ok, mean σ {:.2f} mm, {:.2f} Newton/frame, {:.1f} s", k, plan.runs.size(),
                     r.mesh, r.subject, r.motion, r.sigma_mm, r.newton_per_frame, r.seconds);
    else
      logger()->info("sweep [{}/{}] {} {} {}: FAILED after {} frames: {}", k, plan.runs.size(), r.mesh, r.subject,
                     r.motion, r.frames, r.error);
  };
  std::optional<tbb::global_control> parallelism;
  if (opt.threads > 0)
    parallelism.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));
  const std::size_t per_mesh = plan.per_mesh();
  for (std::size_t m = 0; m < plan.meshes.size(); ++m) {
    const std::size_t first = m * per_mesh;
    run_one(first);
    if (opt.base.solver == "full") {
      for (std::size_t i = first + 1; i < first + per_mesh; ++i) run_one(i);
    } else {
      tbb::parallel_for(
          first + 1, first + per_mesh, [&](std::size_t i) { run_one(i); }, tbb::simple_partitioner());
    }
  }
}

/// sweep.csv, sweep.md and summary.json into the staging folder; returns summary.json's per-mesh counts.
nlohmann::json write_sweep_report(RunFolder& folder, const SweepOptions& opt, const SweepPlan& plan,
                                  double wall_seconds, const Invocation& invocation) {
  const std::vector<sweep::SweepRun>& runs = plan.runs;
  const nlohmann::json counts = sweep::counts_per_mesh(runs);
  const nlohmann::json failures = sweep::failures_json(runs);
  const std::string reduced_text = opt.base.solver == "reduced"
                                       ? fmt::format(" --handles {} --cubature {}{}", opt.base.handles,
                                                     opt.base.cubature, opt.base.affine ? " --affine" : "")
                                       : std::string();
  sweep::write_sweep_csv(folder.stage("sweep.csv"), runs);
  sweep::write_sweep_markdown(
      folder.stage("sweep.md"),
      fmt::format("Sweep: --solver {}, {} frames at {:g} fps", opt.base.solver, opt.base.frames, opt.base.fps),
      {fmt::format("each run is `sflsh simulate --solver {} --mesh M --subject S --motion X --frames {} --integrator "
                   "{} --mass {}{} "
                   "--no-output`",
                   opt.base.solver, opt.base.frames, opt.base.integrator, opt.base.layer.mass, reduced_text),
       fmt::format("{} run(s), {} failed; wall time {:.1f} s on {} thread(s)", runs.size(), failures.size(),
                   wall_seconds, plan.threads),
       "σ: dynamics amplitude per region vertex (docs/physics.md §4); frames: output frames computed, the rest state "
       "included; "
       "retried attempts: substep attempts rejected and repeated (PSD projection, then splitting)"},
      runs);

  nlohmann::json summary = summary_header("sweep", invocation.argc, invocation.argv);
  summary["sweep"] = {{"solver", opt.base.solver},     {"meshes", plan.meshes},
                      {"subjects", plan.subjects},     {"motions", plan.motions},
                      {"frames", opt.base.frames},     {"fps", opt.base.fps},
                      {"substeps", opt.base.substeps}, {"integrator", opt.base.integrator},
                      {"mass", opt.base.layer.mass},   {"threads", plan.threads}};
  if (opt.base.solver == "reduced")
    summary["sweep"]["reduced"] = {{"handles", opt.base.handles},
                                   {"cubature", opt.base.cubature},
                                   {"cubature_weights", opt.base.cubature_weights},
                                   {"affine", opt.base.affine}};
  summary["material"] = material_summary(opt.base.layer, load_layer_material(opt.base.layer));
  summary["counts"] = counts;
  summary["runs"] = runs.size();
  summary["failures"] = failures.size();
  summary["failed_runs"] = failures;
  summary["output"] = {{"table", "sweep.csv"}, {"markdown", "sweep.md"}};
  summary["units"] = {{"sigma", "mm"}, {"seconds", "s"}, {"fps", "output frames per second of solve time"}};
  write_summary(folder, summary, wall_seconds, {.timings_wall_seconds = true});
  return counts;
}

void run_sweep(const SweepOptions& opt, const Invocation& invocation, int size) {
  const auto t_start = Clock::now();
  require(size == 1, "sweep runs on one process (got {}); use --threads for parallel cases", size);
  require(opt.base.frames >= 2, "--frames must be at least 2, got {}", opt.base.frames);
  require(opt.threads >= 0, "--threads must be non-negative, got {}", opt.threads);
  require(opt.base.solver == "full" || opt.base.solver == "reduced", "--solver {}: expected full or reduced",
          opt.base.solver);
  check_layer_settings(opt.base.layer);
  SweepPlan plan = plan_sweep(opt);
  RunFolder run_folder(opt.out);  // the staging folder: the report appears at once when every case has ended
  logger()->info(
      "sweep: {} run(s) ({} mesh(es) × {} subject(s) × {} motion(s)), {} frames, --solver {}, {}", plan.runs.size(),
      plan.meshes.size(), plan.subjects.size(), plan.motions.size(), opt.base.frames, opt.base.solver,
      opt.base.solver == "full" ? std::string("one at a time (PETSc)") : fmt::format("{} thread(s)", plan.threads));
  run_cases(opt, plan);
  const double wall_seconds = seconds_since(t_start);
  const nlohmann::json counts = write_sweep_report(run_folder, opt, plan, wall_seconds, invocation);
  run_folder.commit();

  const long failed = std::count_if(plan.runs.begin(), plan.runs.end(), [](const sweep::SweepRun& r) { return !r.ok; });
  std::string where;
  for (const auto& [mesh, c] : counts.items())
    where +=
        fmt::format("{}{} {}/{}", where.empty() ? "" : ", ", mesh, c["failures"].get<long>(), c["runs"].get<long>());
  if (failed > 0)
    throw_error("sweep: {} of {} runs failed ({}); see {}", failed, plan.runs.size(), where,
                (run_folder.dir() / "sweep.md").string());
  logger()->info("sweep: all {} runs ok in {:.1f} s; wrote {}", plan.runs.size(), wall_seconds,
                 run_folder.dir().string());
}

}  // namespace

void register_sweep_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<SweepOptions>();
  opt->base.solver = "reduced";
  opt->base.frames = 120;
  auto* cmd = app.add_subcommand("sweep",
                                 "Robustness sweep: run every subject × motion × mesh as `sflsh simulate … "
                                 "--no-output` would (in-process, in parallel "
                                 "with --threads) and report each run's status, error, σ, Newton iterations and time "
                                 "(sweep.csv, sweep.md, summary.json). "
                                 "The report is written even when runs fail; the exit code is then 1, with one line "
                                 "saying how many failed and where the "
                                 "table is.");
  cmd->add_option("--solver", opt->base.solver, "full | reduced (full-space runs go one at a time)")
      ->capture_default_str()
      ->check(CLI::IsMember({"full", "reduced"}));
  cmd->add_option("--mesh", opt->meshes, "Layer resolutions, comma-separated: coarse, default, fine")
      ->capture_default_str();
  cmd->add_option("--subjects", opt->subjects,
                  "Subjects, comma-separated: names, table1 (DYNA_1–5, TEST_1–5), open (every OPEN_*), all")
      ->capture_default_str();
  cmd->add_option("--motions", opt->motions, "Motions, comma-separated: procedural names, AMASS .npz paths, or all")
      ->capture_default_str();
  add_frame_options(*cmd, opt->base.frames, opt->base.fps, opt->base.substeps);
  cmd->add_flag("--allow-long", opt->base.allow_long,
                "Run cases whose work estimate exceeds the limits of docs/scenes.md (\"Input limits\")");
  cmd->add_option("--threads", opt->threads,
                  "Runs in parallel (TBB; 0: all cores; full-space runs always go one at a time)")
      ->capture_default_str();
  add_reduced_run_options(*cmd, opt->base);
  add_integrator_option(*cmd, opt->base.integrator);
  add_layer_options(*cmd, opt->base.layer);
  add_mass_option(*cmd, opt->base.layer);
  cmd->add_option("--out", opt->out, "Output folder (sweep.csv, sweep.md, summary.json)")->required();
  cmd->callback(
      [opt, invocation] { with_petsc(invocation, [&](int, int size) { run_sweep(*opt, invocation, size); }); });
}

}  // namespace sflsh::app
