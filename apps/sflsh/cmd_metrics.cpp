// sflsh metrics: the paper's dynamics metric (docs/physics.md §4) on DYNA registrations. Fits per-frame pose
// (and β when not given) to one sequence of a DYNA HDF5 file, pulls the registrations back to the neutral
// pose and writes the per-vertex σ, σ_n, σ_t [mm] on the shaped template surface, plus a table.
// `sflsh metrics --dyna FILE.h5 --list` lists the subjects and sequences of a file.
#include "commands.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/input_file.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>
#include <sflsh/validate/dynamics_report.hpp>
#include <sflsh/validate/pose_fit.hpp>
#include <sflsh/validate/registration_metrics.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <iostream>
#include <memory>

namespace sflsh::app {

namespace {

struct MetricsOptions {
  std::string dyna;
  std::string sequence;
  bool list = false;
  SubjectOptions subject;
  int frames = 0;
  double soft_weight = 0.05;
  std::string out;
};

void list_file(const validate::DynaFile& file) {
  std::cout << fmt::format("{}: {} sequences, {} vertices, {} faces\n", file.path().string(), file.keys().size(),
                           file.num_vertices(), file.faces().rows());
  for (const std::string& subject : file.subjects()) {
    std::cout << subject << ":";
    for (const std::string& sequence : file.sequences(subject)) {
      const std::string key = sequence.empty() ? subject : subject + "_" + sequence;
      std::cout << fmt::format(" {} ({} frames)", sequence.empty() ? key : sequence, file.info(key).frames);
    }
    std::cout << "\n";
  }
}

nlohmann::json vector_json(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

void run_metrics(const MetricsOptions& opt, const Invocation& invocation) {
  const auto t_start = std::chrono::steady_clock::now();
  require(!opt.dyna.empty(), "metrics: --dyna FILE.h5 is required");
  require_input_file(opt.dyna, "a DYNA registration .h5 file");
  const validate::DynaFile file(opt.dyna);
  if (opt.list) {
    list_file(file);
    return;
  }
  require(!opt.sequence.empty(), "metrics: --sequence KEY is required (see `sflsh metrics --dyna {} --list`)",
          opt.dyna);
  require(!opt.out.empty(), "metrics: --out DIR is required");
  require(opt.frames >= 0, "metrics: --frames must be non-negative, got {}", opt.frames);
  require(opt.soft_weight >= 0.0 && opt.soft_weight <= 1.0, "metrics: --soft-weight must be in [0, 1], got {}",
          opt.soft_weight);

  file.info(opt.sequence);  // an unknown sequence is named (with the file's list) before the body is loaded
  const body::BodyModel model = load_selected_body(opt.subject);
  file.require_vertices(model);
  const validate::DynaSequence sequence = file.read(opt.sequence, opt.frames);  // reads only the first N frames
  require(sequence.num_frames() >= 2, "metrics: sequence '{}' has {} frame(s), σ needs at least 2", opt.sequence,
          sequence.num_frames());
  std::optional<body::Betas> given_beta;
  if (!opt.subject.betas.empty()) given_beta = body::parse_betas(opt.subject.betas);

  const std::vector<int> soft = validate::soft_region_vertices(model);
  validate::PoseFitOptions fit_options;
  fit_options.soft_vertices = soft;
  fit_options.soft_weight = opt.soft_weight;
  fit_options.progress = true;
  logger()->info("metrics: {} frames of '{}' ({} vertices, {} in the soft region), β {}", sequence.num_frames(),
                 opt.sequence, model.num_vertices(), soft.size(), given_beta ? "given" : "fitted");
  validate::RegistrationMetrics measured =
      validate::registration_metrics(model, sequence.frames, sequence.fps, given_beta, fit_options);
  validate::PoseFitResult& fit = measured.fit;
  fit.motion.name = opt.sequence;
  fit.motion.source = opt.dyna;
  const validate::DynamicsResult& dynamics = measured.dynamics;
  const double metrics_seconds = measured.metrics_seconds;

  RunFolder run(opt.out);
  validate::write_dynamics_vtp(run.stage("metrics.vtp"), body::shaped_template(model, fit.beta), model.faces, dynamics);
  validate::write_dynamics_csv(run.stage("metrics.csv"), dynamics);
  body::save_amass(run.stage("motion.npz"), fit.motion);

  nlohmann::json summary = summary_header("metrics", invocation.argc, invocation.argv);
  summary["dyna"] = {{"file", opt.dyna},
                     {"sequence", opt.sequence},
                     {"subject", validate::subject_of(opt.sequence)},
                     {"frames", sequence.num_frames()},
                     {"fps", sequence.fps},
                     {"vertices", file.num_vertices()}};
  summary["body"] = body::body_label(opt.subject);
  summary["beta"] = vector_json(fit.beta);
  summary["beta_fitted"] = fit.beta_fitted;
  nlohmann::json per_frame = nlohmann::json::array();
  for (const validate::FrameFitReport& f : fit.frames)
    per_frame.push_back({{"frame", f.frame},
                         {"rms_mm", 1e3 * f.rms},
                         {"rms_rigid_mm", 1e3 * f.rms_rigid},
                         {"iterations", f.iterations},
                         {"evaluations", f.evaluations},
                         {"converged", f.converged},
                         {"status", f.status}});
  summary["fit"] = {{"solver", "Levenberg-Marquardt (Eigen, MINPACK lmder)"},
                    {"soft_weight", opt.soft_weight},
                    {"shape_iterations", fit.shape_iterations},
                    {"shape_converged", fit.shape_converged},
                    {"vertex_stride", fit_options.vertex_stride},
                    {"mean_rms_mm", 1e3 * fit.mean_rms},
                    {"max_rms_mm", 1e3 * fit.max_rms},
                    {"unconverged_frames", fit.unconverged_frames},
                    {"seconds", fit.seconds},
                    {"frames", per_frame}};
  summary["dynamics"] = validate::dynamics_summary(dynamics);
  summary["output"] = {{"surface", "metrics.vtp"}, {"table", "metrics.csv"}, {"motion", "motion.npz"}};
  summary["timings"] = {
      {"fit_seconds", fit.seconds},
      {"metrics_seconds", metrics_seconds},
      {"total_seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count()}};
  write_json(run.stage("summary.json"), summary);
  run.commit();
  logger()->info(
      "metrics: mean σ = {:.2f} mm over the soft region ({:.2f} mm over all vertices); fit RMS {:.2f} mm (max {:.2f}), "
      "{} s",
      1e3 * dynamics.mean_sigma_soft(), 1e3 * dynamics.mean_sigma_all(), 1e3 * fit.mean_rms, 1e3 * fit.max_rms,
      fit.seconds);
  if (fit.unconverged_frames > 0)
    logger()->warn("metrics: {} frame(s) of the pose fit did not converge (see summary.json fit.frames)",
                   fit.unconverged_frames);
}

}  // namespace

void register_metrics_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<MetricsOptions>();
  auto* cmd = app.add_subcommand(
      "metrics",
      "Dynamics metric of DYNA registrations: fit pose (and β) per frame, pull back to the neutral pose, write σ, σ_n, "
      "σ_t [mm] "
      "per vertex (metrics.vtp, metrics.csv, summary.json). --list shows a file's subjects and sequences.");
  cmd->add_option("--dyna", opt->dyna,
                  "DYNA registration file (HDF5: faces + <subject>_<sequence> datasets of shape (V, 3, T))")
      ->required();
  cmd->add_flag("--list", opt->list, "List the subjects and sequences of the file and exit");
  cmd->add_option("--sequence", opt->sequence, "Dataset key <subject>_<sequence>, e.g. 50004_jiggle_on_toes");
  add_body_option(*cmd, opt->subject);
  cmd->add_option("--betas", opt->subject.betas,
                  "Shape β (up to 10 numbers); fitted from the registrations when absent");
  cmd->add_option("--frames", opt->frames, "Use only the first N frames (0: all)");
  cmd->add_option("--soft-weight", opt->soft_weight, "Weight of soft-region vertices in the pose fit (1 elsewhere)");
  cmd->add_option("--out", opt->out, "Output folder");
  cmd->callback([opt, invocation] { run_metrics(*opt, invocation); });
}

}  // namespace sflsh::app
