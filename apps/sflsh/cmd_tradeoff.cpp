// sflsh tradeoff: what accuracy costs in time. The command's options and its `quick` and `full` presets; the study
// itself, with the checks of its options, is tradeoff_study.cpp (docs/tradeoff.md says exactly what is measured).
#include "commands.hpp"
#include "layer_setup.hpp"
#include "tradeoff_study.hpp"

#include <sflsh/core/error.hpp>

#include <memory>

namespace sflsh::app {

namespace {

/// The `full` preset; `quick` is the defaults of TradeoffOptions. Options given on the command line win.
void apply_preset(TradeoffOptions& o, const CLI::App& cmd) {
  require(o.preset == "quick" || o.preset == "full", "--preset {}: expected quick or full", o.preset);
  if (o.preset != "full") return;
  auto unset = [&](const char* name) { return cmd.count(name) == 0; };
  if (unset("--frames")) o.frames = 30;
  if (unset("--reference-mesh")) o.reference_mesh = "default";
  if (unset("--reference-substeps")) o.reference_substeps = 16;
  if (unset("--reference-check")) o.reference_checks = {"time", "space"};
  if (unset("--meshes")) o.meshes = {"coarse", "default"};
  if (unset("--substeps")) o.substeps = {1, 2, 4};
  if (unset("--integrators")) o.integrators = {"backward_euler", "newmark"};
  if (unset("--reduced-meshes")) o.reduced_meshes = {"coarse", "default"};
  if (unset("--handles")) o.handles = {30, 86, 200};
  if (unset("--cubature")) o.cubature = {200, 400, 800};
  if (unset("--reduced-substeps")) o.reduced_substeps = {1, 2, 4};
}

}  // namespace

void register_tradeoff_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<TradeoffOptions>();
  auto* cmd = app.add_subcommand("tradeoff",
                                 "What accuracy costs in time: one case run by a reference, full-space backward Euler "
                                 "on several meshes and steps and reduced "
                                 "models (handles × cubature × steps), scored against the reference; writes "
                                 "tradeoff.csv/.md/.png and summary.json with the "
                                 "Pareto front and the cheapest configuration within --budget-mm / --budget-relative.");
  cmd->add_option("--preset", opt->preset,
                  "quick (minutes on 2 cores; reference: Newmark + consistent masses at 1/960 s on the coarse mesh) | "
                  "full (reference: the same "
                  "at 1/480 s on the default mesh, checked against a finer step and the fine mesh)")
      ->check(CLI::IsMember({"quick", "full"}));
  add_body_option(*cmd, opt->subject);
  add_subject_options(*cmd, opt->subject);
  cmd->add_option("--motion", opt->motion, "Motion: a procedural name (sflsh motion list) or an AMASS .npz path")
      ->capture_default_str();
  cmd->add_option("--frames", opt->frames, "Output frames (quick 8, full 60)");
  cmd->add_option("--fps", opt->fps, "Output frame rate (and motion sampling); every step is 1 / (fps · substeps)")
      ->capture_default_str();
  cmd->add_option("--reference", opt->reference,
                  "newmark | bdf2 | backward_euler (the full-space solver at --reference-substeps) | sundials "
                  "(adaptive, error-controlled)")
      ->check(CLI::IsMember({"sundials", "backward_euler", "bdf2", "newmark"}));
  cmd->add_option("--reference-mass", opt->reference_mass, "Mass of the reference: lumped | consistent")
      ->check(CLI::IsMember({"lumped", "consistent"}))
      ->capture_default_str();
  cmd->add_option("--reference-check", opt->reference_checks,
                  "How converged the reference is: time (twice the substeps) and/or space (the next finer mesh), "
                  "comma-separated")
      ->delimiter(',')
      ->check(CLI::IsMember({"time", "space"}));
  cmd->add_option("--reference-check-frames", opt->reference_check_frames, "Frames the reference checks run")
      ->capture_default_str();
  cmd->add_option("--integrators", opt->integrators, "Integrators of the full-space and reduced rows, comma-separated")
      ->delimiter(',')
      ->check(CLI::IsMember({"backward_euler", "bdf2", "newmark"}));
  cmd->add_option("--masses", opt->masses, "Masses of the full-space and reduced rows, comma-separated")
      ->delimiter(',')
      ->check(CLI::IsMember({"lumped", "consistent"}));
  cmd->add_option("--reference-mesh", opt->reference_mesh, "Mesh of the reference (quick coarse, full fine)")
      ->check(CLI::IsMember({"coarse", "default", "fine"}));
  cmd->add_option("--reference-substeps", opt->reference_substeps,
                  "Substeps per frame of a stepping reference (quick 32, full 16)");
  cmd->add_option("--rtol", opt->rtol, "SUNDIALS reference: relative tolerance")->capture_default_str();
  cmd->add_option("--atol", opt->atol, "SUNDIALS reference: absolute tolerance [m, m/s]")->capture_default_str();
  cmd->add_option("--meshes,--mesh", opt->meshes,
                  "Meshes of the full-space rows, comma-separated (--mesh: the spelling of the other commands)")
      ->delimiter(',')
      ->check(CLI::IsMember({"coarse", "default", "fine"}));
  cmd->add_option("--substeps", opt->substeps,
                  "Substeps per frame of the full-space rows, comma-separated (1,2,4,8 at 30 fps: 1/30 to 1/240 s)")
      ->delimiter(',');
  cmd->add_option("--reduced-meshes", opt->reduced_meshes, "Meshes of the reduced rows, comma-separated (empty: none)")
      ->delimiter(',')
      ->check(CLI::IsMember({"coarse", "default", "fine"}));
  cmd->add_option("--handles", opt->handles, "Point-handle counts of the reduced rows, comma-separated")
      ->delimiter(',');
  cmd->add_option("--cubature", opt->cubature,
                  "Cubature tet counts K of the reduced rows, comma-separated (0 = every tet)")
      ->delimiter(',');
  cmd->add_option("--reduced-substeps", opt->reduced_substeps,
                  "Substeps per frame of the reduced rows, comma-separated")
      ->delimiter(',');
  cmd->add_option("--budget-mm", opt->budget_mm,
                  "Error budget: largest RMS error [mm] (the recommendation is the cheapest row within it)");
  cmd->add_option("--budget-relative", opt->budget_relative, "Error budget: largest relative error");
  add_reduced_options(*cmd, opt->reduced);
  add_layer_options(*cmd, opt->layer);
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation, cmd] {
    apply_preset(*opt, *cmd);
    with_petsc(invocation, [&](int rank, int size) { run_tradeoff(*opt, invocation, rank, size); });
  });
}

}  // namespace sflsh::app
