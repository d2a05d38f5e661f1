// sflsh validate [--preset quick|paper] --out DIR: the paper's experiments (Table 2, cross-validation and
// the λ sweep, parameter covariance, parameter recovery) on synthetic ground truth from the full-space
// solver. Runs in parallel with mpirun -n P (simulations are shared among ranks) and --threads T per rank.
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/validate/experiments.hpp>

#include <fmt/format.h>

namespace sflsh::app {

namespace {

struct ValidateOptions {
  std::string preset = "quick";
  std::string out;
  std::string mesh;
  int handles = 0;
  int cubature = -2;
  int frames = -1;
  int iterations = 0;
  double loss_rtol = -1.0;
  int warm_iterations = -1;
  int threads = 0;
  std::vector<int> stages;
  std::vector<double> lambdas, lambdas_l2, lambdas_ours;
  std::vector<std::string> train_subjects, test_subjects, train_motions, test_motions;
  bool no_cross_validation = false;
  bool no_lambda_warm_start = false;
  std::string lambda_rule = "one-se";
  int lambda_extensions = -1;  ///< -1: the preset's
  int fit_groups = 1;
  std::string jacobian = "exact";
  std::vector<std::string> dyna;
  std::string body;
  std::string truth_model;
  bool quiet = false;
};

void run_validate(const ValidateOptions& o, const Invocation& invocation) {
  validate::ValidateConfig config = validate::ValidateConfig::from_preset(o.preset);
  if (!o.mesh.empty()) config.mesh = meshing::parse_size_preset(o.mesh);
  if (o.handles > 0) config.point_handles = o.handles;
  if (o.cubature >= -1) config.cubature = o.cubature;
  if (o.frames >= 0) config.frames = o.frames;
  if (o.iterations > 0) config.iterations = o.iterations;
  if (o.loss_rtol >= 0.0) config.loss_rtol = o.loss_rtol;
  if (o.warm_iterations >= 0) config.warm_iterations = o.warm_iterations;
  config.threads = o.threads;
  if (!o.stages.empty()) config.stages = o.stages;
  if (!o.lambdas.empty()) config.lambdas = o.lambdas;
  if (!o.lambdas_l2.empty()) config.lambdas_of["l2"] = o.lambdas_l2;
  if (!o.lambdas_ours.empty()) config.lambdas_of["ours"] = o.lambdas_ours;
  if (!o.train_subjects.empty()) {
    config.train_subjects = o.train_subjects;
    config.preset_subjects_overridden = true;
  }
  for (const std::string& f : o.dyna) config.dyna.emplace_back(f);
  config.body_path = o.body;
  config.truth_model = o.truth_model;
  if (!o.test_subjects.empty()) config.test_subjects = o.test_subjects;
  if (!o.train_motions.empty()) config.train_motions = o.train_motions;
  if (!o.test_motions.empty()) config.test_motions = o.test_motions;
  if (o.no_cross_validation) config.cross_validation = false;
  if (o.no_lambda_warm_start) config.lambda_warm_start = false;
  if (o.lambda_extensions >= 0) config.lambda_extensions = o.lambda_extensions;
  config.lambda_rule = validate::parse_lambda_rule(o.lambda_rule, "validate: --lambda-rule");
  config.fit_groups = o.fit_groups;
  config.jacobian = o.jacobian;
  config.progress = !o.quiet;
  const nlohmann::json summary =
      validate::run_validation(config, o.out, summary_header("validate", invocation.argc, invocation.argv));
  if (summary.contains("table2")) {
    for (const auto& row : summary["table2"])
      logger()->info("{:<30} train motions avg {:.3f} mm · test motions avg {:.3f} mm", row["row"].get<std::string>(),
                     row["train_motions"]["avg"].get<double>(), row["test_motions"]["avg"].get<double>());
  }
  logger()->info("validate: wrote {}", o.out);
}

}  // namespace

void register_validate_commands(CLI::App& app, const Invocation& invocation) {
  auto o = std::make_shared<ValidateOptions>();
  auto* cmd = app.add_subcommand(
      "validate",
      "The paper's experiments on synthetic ground truth (full-space simulations with a hidden shape-dependent "
      "material): independent fits, leave-one-out cross-validation with a λ sweep, full optimizations with L2 and "
      "the local regularizer, generalization to test subjects. Writes table2.csv/.md, cross_validation.csv, "
      "lambda_sweep.csv/.png, covariance.csv, parameter_error.csv, dynamics.vtp, fitted materials and summary.json. "
      "An interrupted run resumes from DIR/state. Parallel: mpirun -n P and --threads T.");
  cmd->add_option("--preset", o->preset, "quick (minutes) or paper (the full configuration)")
      ->check(CLI::IsMember({"quick", "paper"}));
  cmd->add_option("--out", o->out, "Output folder")->required();
  add_mesh_option(*cmd, o->mesh, false, "preset: coarse");  // empty: the preset's
  cmd->add_option("--handles", o->handles, "Point handles of the reduced model")->check(CLI::PositiveNumber);
  cmd->add_option("--cubature", o->cubature, "Cubature tets (0 = every tet, -1 = auto)")
      ->check(CLI::Range(-1, 1 << 30));
  cmd->add_option("--frames", o->frames, "Frames per clip (0 = the motions' default length)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--stages", o->stages, "Control-point counts, e.g. 1,12,24,84")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--iterations", o->iterations,
                  "Trust-region iterations per stage at most: the safety net (fits.csv's reason says when it ended a "
                  "stage)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--loss-rtol", o->loss_rtol,
                  "A stage converges when two accepted iterations lower its loss by at most this fraction (default "
                  "1e-3; 0: only the gradient and trust-region tests)")
      ->check(CLI::Range(0.0, 0.5));
  cmd->add_option("--warm-iterations", o->warm_iterations,
                  "Trust-region iterations of each warm-started fit of the λ sweep (0 = --iterations; paper preset: 3)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--lambdas", o->lambdas, "λ values of the cross-validation sweep, e.g. 0.01,0.1,1")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--lambdas-l2", o->lambdas_l2, "The L2 regularizer's own λ grid (default: --lambdas)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--lambdas-ours", o->lambdas_ours,
                  "The local regularizer's own λ grid (default: --lambdas); its metric charges other directions than "
                  "L2, so its minimum can lie elsewhere")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--train-subjects", o->train_subjects, "Comma-separated subject names (data/*subjects.toml)")
      ->delimiter(',');
  cmd->add_option("--test-subjects", o->test_subjects, "Comma-separated subject names")->delimiter(',');
  cmd->add_option("--train-motions", o->train_motions, "Comma-separated motion names")->delimiter(',');
  cmd->add_option("--test-motions", o->test_motions, "Comma-separated motion names")->delimiter(',');
  cmd->add_option("--dyna", o->dyna,
                  "DYNA registration files (HDF5): their subjects become the train subjects and their "
                  "sequences the ground truth (poses and β fitted); test subjects come from --test-subjects")
      ->check(CLI::ExistingFile);
  cmd->add_option("--body", o->body, "Body model .npz (default: the open body; SMPL for DYNA data)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--truth-model", o->truth_model,
                  "Shape model file (TOML, as `sflsh shapefit` writes) that defines the synthetic truth's material "
                  "instead of the built-in one (docs/fit.md)");
  cmd->add_option("--threads", o->threads, "Threads per process (0 = all)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--jacobian", o->jacobian,
                  "dσ/dq: exact (sensitivities, thickness through the retarget; default), hybrid (thickness columns "
                  "by differences) or fd (differences of every column, the paper's method)")
      ->check(CLI::IsMember({"exact", "hybrid", "fd"}));
  cmd->add_option("--lambda-extensions", o->lambda_extensions,
                  "At most this many λs added half a decade beyond a grid's end while the CV error is least there "
                  "(0: the grids as given; preset: quick 2, paper 6)")
      ->check(CLI::Range(0, 24));
  cmd->add_option("--lambda-rule", o->lambda_rule,
                  "How λ is chosen from the sweep: one-se (the largest λ whose mean CV error is within one standard "
                  "error of the least; default) or min (the least CV error, the paper's)")
      ->check(CLI::IsMember({"one-se", "one-standard-error", "min", "minimum"}));
  cmd->add_flag("--no-cross-validation", o->no_cross_validation,
                "Skip the leave-one-out fits (λ = the first of --lambdas)");
  cmd->add_option("--fit-groups", o->fit_groups,
                  "With mpirun -n P: split the ranks into G groups that run whole fits side by side (each fit's "
                  "simulations shared by its group's ranks); DIR/state must be visible to every rank")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-lambda-warm-start", o->no_lambda_warm_start,
                "Fit every λ of the leave-one-out sweep through every stage from the neutral start (default: the "
                "largest λ does, each smaller λ continues at the last stage from the previous one)");
  cmd->add_flag("--quiet", o->quiet, "No progress lines");
  cmd->callback([o, invocation] { with_petsc(invocation, [&](int, int) { run_validate(*o, invocation); }); });
}

}  // namespace sflsh::app
