#pragma once
// The sflsh command-line interface: each command group registers its subcommands on the app.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/body/subject_selection.hpp>

#include <CLI/CLI.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::app {

/// argc/argv of the process, for summary.json.
struct Invocation {
  int argc = 0;
  const char* const* argv = nullptr;
  std::vector<std::string> petsc_options;  ///< -snes_*, -ksp_*, -pc_*, … tokens (main.cpp splits them off)
};

void register_body_commands(CLI::App& app, const Invocation& invocation);
void register_motion_commands(CLI::App& app, const Invocation& invocation);
void register_mesh_commands(CLI::App& app, const Invocation& invocation);
void register_material_commands(CLI::App& app, const Invocation& invocation);
/// `material show` (cmd_material_show.cpp), added to the `material` group by register_material_commands.
void add_material_show_command(CLI::App& material, const Invocation& invocation);
/// `sflsh verify PROBLEM.toml --out DIR` (cmd_verify.cpp).
void register_verify_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh simulate --solver full …` (cmd_simulate.cpp).
void register_simulate_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh compare`: full space against a sweep of reduced models (cmd_compare.cpp).
void register_compare_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh sweep`: subjects × motions × meshes through the simulate code path, failures reported (cmd_sweep.cpp).
void register_sweep_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh tradeoff`: accuracy against time over models, meshes and steps (cmd_tradeoff.cpp).
void register_tradeoff_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh validate`: the paper's experiments on synthetic ground truth (cmd_validate.cpp).
void register_validate_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh shapefit`: the shape regression of SFLSH eqs. 1, 4, 5 on material files (cmd_shapefit.cpp).
void register_shapefit_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh groundtruth`: synthetic ground truth as DYNA-layout HDF5 (cmd_groundtruth.cpp).
void register_groundtruth_commands(CLI::App& app, const Invocation& invocation);
/// `sflsh metrics --dyna FILE.h5 --sequence KEY … --out DIR` and `--list` (cmd_metrics.cpp).
void register_metrics_commands(CLI::App& app, const Invocation& invocation);

/// `sflsh render --run DIR --out FILE.png`: a simulation's posed body coloured by its soft-tissue motion
/// (cmd_render.cpp).
void register_render_commands(CLI::App& app, const Invocation& invocation);

/// Runs `body` with PETSc (and MPI) initialized from the invocation's PETSc options. Under mpirun, an
/// error on any rank is printed with the rank and stops every rank (MPI_Abort) instead of deadlocking.
void with_petsc(const Invocation& invocation, const std::function<void(int rank, int size)>& body);

/// Options that choose a body model and a subject: --body PATH, --subject NAME | --betas "…" (one definition in
/// the body library, shared with the Python module).
using SubjectOptions = body::SubjectSelection;
using body::load_selected_body;
using body::selected_betas;
void add_body_option(CLI::App& cmd, SubjectOptions& options);
/// Adds --subject and --betas (mutually exclusive).
void add_subject_options(CLI::App& cmd, SubjectOptions& options);

/// Index of each vertex's largest skinning weight (n×1), for the `skin_weights_argmax` field.
Eigen::MatrixXd dominant_joint(const body::BodyModel& model);

}  // namespace sflsh::app
