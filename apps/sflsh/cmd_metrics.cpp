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
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>
#include <sflsh/validate/dynamics_report.hpp>
#include <sflsh/validate/pose_fit.hpp>
#include <sflsh/validate/registration_metrics.hpp>
#include <sflsh/validate/synthetic_dyna.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>

namespace sflsh::app {

namespace {

struct MetricsOptions {
  std::string dyna;
  std::string sequence;
  bool list = false;
  SubjectOptions subject;
  int frames = 0;
  double soft_weight = 0.05;
  std::string pose_weights = "rigidity";
  double rigid_depth = validate::PoseFitOptions{}.rigid_depth;
  double temporal_weight = validate::PoseFitOptions{}.temporal_weight;
  std::string out;
  // --synthesize MOTION: write a synthetic DYNA file with known soft-tissue motion instead of measuring one.
  std::string synthesize;
  double amplitude_mm = 6.0;
  double frequency = 3.0;
  double angle_degrees = 45.0;
  std::string regions;
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

/// `sflsh metrics --synthesize MOTION --out DIR`: DIR/soft_motion.h5 (dataset SYNTH_<motion>), DIR/truth.csv
/// (the known σ per vertex, the layout of metrics.csv) and DIR/summary.json (the spec and the known means).
void run_synthesize(const MetricsOptions& opt, const Invocation& invocation) {
  const auto t_start = std::chrono::steady_clock::now();
  require(!opt.out.empty(), "metrics: --out DIR is required");
  validate::SyntheticSoftMotion spec;
  spec.motion = opt.synthesize;
  spec.frames = opt.frames > 0 ? opt.frames : 300;
  spec.amplitude = 1e-3 * opt.amplitude_mm;
  spec.frequency = opt.frequency;
  spec.angle = opt.angle_degrees * std::numbers::pi / 180.0;
  if (!opt.regions.empty()) {
    spec.regions.clear();
    std::stringstream list(opt.regions);
    for (std::string name; std::getline(list, name, ',');) spec.regions.push_back(name);
  }
  const body::BodyModel model = load_selected_body(opt.subject);
  if (!opt.subject.betas.empty()) spec.beta = body::parse_betas(opt.subject.betas);
  const validate::SyntheticSoftSequence s = validate::synthetic_soft_motion(model, spec);
  RunFolder run(opt.out);
  validate::write_dyna_file(run.stage("soft_motion.h5"), model.faces, {validate::to_dyna_sequence(s, spec, "SYNTH")});
  validate::write_dynamics_csv(run.stage("truth.csv"), s.truth);
  nlohmann::json summary = summary_header("metrics", invocation.argc, invocation.argv);
  summary["synthetic"] = {{"file", "soft_motion.h5"},
                          {"sequence", "SYNTH_" + spec.motion},
                          {"frames", spec.frames},
                          {"fps", spec.fps},
                          {"beta", vector_json(spec.beta)},
                          {"regions", spec.regions},
                          {"amplitude_mm", opt.amplitude_mm},
                          {"frequency_hz", spec.frequency},
                          {"angle_degrees", opt.angle_degrees},
                          {"radius_mm", 1e3 * spec.radius},
                          {"moving_vertices", s.moving_vertices.size()}};
  summary["truth"] = validate::dynamics_summary(s.truth);
  write_summary(run, summary, seconds_since(t_start));
  run.commit();
  logger()->info(
      "metrics: wrote {} frames of {} with {} mm at {} Hz on {}: known mean σ {:.3f} mm over the soft region",
      spec.frames, spec.motion, opt.amplitude_mm, spec.frequency, opt.regions.empty() ? "every region" : opt.regions,
      1e3 * s.truth.mean_sigma_soft());
}

/// The options of a measurement (not --list, not --synthesize), checked before anything is read.
void check_measure_options(const MetricsOptions& opt) {
  require(!opt.sequence.empty(), "metrics: --sequence KEY is required (see `sflsh metrics --dyna {} --list`)",
          opt.dyna);
  require(!opt.out.empty(), "metrics: --out DIR is required");
  require(opt.frames >= 0, "metrics: --frames must be non-negative, got {}", opt.frames);
  require(opt.soft_weight >= 0.0 && opt.soft_weight <= 1.0, "metrics: --soft-weight must be in [0, 1], got {}",
          opt.soft_weight);
  validate::parse_weighting(opt.pose_weights);  // a bad name fails before anything is read
  require(opt.rigid_depth > 0.0, "metrics: --rigid-depth must be positive, got {}", opt.rigid_depth);
  require(opt.temporal_weight >= 0.0, "metrics: --temporal-weight must be non-negative, got {}", opt.temporal_weight);
}

void run_metrics(const MetricsOptions& opt, const Invocation& invocation) {
  const auto t_start = std::chrono::steady_clock::now();
  if (!opt.synthesize.empty()) {
    run_synthesize(opt, invocation);
    return;
  }
  require(!opt.dyna.empty(), "metrics: --dyna FILE.h5 is required");
  require_input_file(opt.dyna, "a DYNA registration .h5 file");
  const validate::DynaFile file(opt.dyna);
  if (opt.list) {
    list_file(file);
    return;
  }
  check_measure_options(opt);
  file.info(opt.sequence);  // an unknown sequence is named (with the file's list) before the body is loaded
  const body::BodyModel model = load_selected_body(opt.subject);
  file.require_vertices(model);
  const validate::DynaSequence sequence = file.read(opt.sequence, opt.frames);  // reads only the first N frames
  require(sequence.num_frames() >= 2, "{}: {}: {} frame{} {}, expected at least 2 (σ is a spread over time)", opt.dyna,
          opt.sequence, sequence.num_frames(), sequence.num_frames() == 1 ? "" : "s",
          opt.frames > 0 && opt.frames < file.info(opt.sequence).frames ? fmt::format("read (--frames {})", opt.frames)
                                                                        : std::string("in the file"));
  std::optional<body::Betas> given_beta;
  if (!opt.subject.betas.empty()) given_beta = body::parse_betas(opt.subject.betas);

  const std::vector<int> soft = validate::soft_region_vertices(model);
  validate::PoseFitOptions fit_options;
  fit_options.soft_vertices = soft;
  fit_options.soft_weight = opt.soft_weight;
  fit_options.weighting = validate::parse_weighting(opt.pose_weights);
  fit_options.rigid_depth = opt.rigid_depth;
  fit_options.temporal_weight = opt.temporal_weight;
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
                    {"weighting", validate::weighting_name(fit_options.weighting)},
                    {"soft_weight", opt.soft_weight},
                    {"rigid_depth_m", opt.rigid_depth},
                    {"temporal_weight_m2_per_rad2", opt.temporal_weight},
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
  summary["timings"] = {{"fit_seconds", fit.seconds}, {"metrics_seconds", metrics_seconds}};
  write_summary(run, summary, seconds_since(t_start));
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
                  "DYNA registration file (HDF5: faces + <subject>_<sequence> datasets of shape (V, 3, T))");
  cmd->add_flag("--list", opt->list, "List the subjects and sequences of the file and exit");
  cmd->add_option("--sequence", opt->sequence, "Dataset key <subject>_<sequence>, e.g. 50004_jiggle_on_toes");
  add_body_option(*cmd, opt->subject);
  cmd->add_option("--betas", opt->subject.betas,
                  "Shape β (up to 10 numbers); fitted from the registrations when absent");
  cmd->add_option("--frames", opt->frames,
                  "Use only the first N frames (0: all); --synthesize: frames to write (0: 300)");
  cmd->add_option("--soft-weight", opt->soft_weight,
                  "--pose-weights soft_weight: weight of soft-region vertices in the pose fit (1 elsewhere)");
  cmd->add_option("--pose-weights", opt->pose_weights,
                  "Pose-fit weighting: rigidity (default: rigidity weights and a temporal prior on θ) or soft_weight "
                  "(the earlier fit: --soft-weight on the soft region, 1 elsewhere)");
  cmd->add_option("--rigid-depth", opt->rigid_depth,
                  "rigidity: D_0 [m], soft vertices nearer the bones count as rigid (w = (D_0/D)^4 beyond)");
  cmd->add_option("--temporal-weight", opt->temporal_weight,
                  "rigidity: weight [m²/rad²] of the prior on θ's second difference in the first fit (0: none); the "
                  "reweighting passes scale it with the measured noise σ_0² (docs/validate.md)");
  cmd->add_option("--synthesize", opt->synthesize,
                  "Write a synthetic DYNA file with known soft-tissue motion over this procedural motion to --out "
                  "(soft_motion.h5, truth.csv, summary.json) instead of measuring one");
  cmd->add_option("--amplitude", opt->amplitude_mm, "--synthesize: peak soft-tissue displacement [mm] (default 6)");
  cmd->add_option("--frequency", opt->frequency, "--synthesize: oscillation frequency [Hz] (default 3)");
  cmd->add_option("--angle", opt->angle_degrees,
                  "--synthesize: direction, 0 normal … 90 tangential (downwards) [degrees] (default 45)");
  cmd->add_option("--regions", opt->regions, "--synthesize: comma-separated chest,belly,buttocks,thighs (default all)");
  cmd->add_option("--out", opt->out, "Output folder");
  cmd->callback([opt, invocation] { run_metrics(*opt, invocation); });
}

}  // namespace sflsh::app
