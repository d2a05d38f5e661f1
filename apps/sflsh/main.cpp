// sflsh — shape-dependent soft-flesh avatars. Command-line entry point.
#include "commands.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/petsc_session.hpp>

#include <mpi.h>

#include <iostream>

namespace {

/// Under mpirun an error on one rank must stop all of them (the others may wait in a collective call).
[[noreturn]] void abort_other_ranks_if_parallel() {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  int size = 1;
  if (initialized && !finalized) MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size > 1) MPI_Abort(MPI_COMM_WORLD, 1);
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sflsh: physics-based soft-flesh avatars with shape-dependent tissue parameters"};
  app.set_version_flag("--version", sflsh::version());
  app.require_subcommand(1);
  app.fallthrough();
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "Logging level: trace, debug, info, warn, error, off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors (same as --log-level warn)");

  // PETSc options (-snes_*, -ksp_*, -pc_*, -options_file, …) go to PETSc, the rest to CLI11.
  const sflsh::fullspace::SplitArguments split = sflsh::fullspace::split_petsc_arguments(argc, argv);
  std::vector<const char*> own_argv;
  for (const auto& a : split.own) own_argv.push_back(a.c_str());
  const int own_argc = static_cast<int>(own_argv.size());

  const sflsh::app::Invocation invocation{argc, argv, split.petsc};
  sflsh::app::register_body_commands(app, invocation);
  sflsh::app::register_motion_commands(app, invocation);
  sflsh::app::register_mesh_commands(app, invocation);
  sflsh::app::register_material_commands(app, invocation);
  sflsh::app::register_verify_commands(app, invocation);
  sflsh::app::register_simulate_commands(app, invocation);
  sflsh::app::register_compare_commands(app, invocation);
  sflsh::app::register_sweep_commands(app, invocation);
  sflsh::app::register_tradeoff_commands(app, invocation);
  sflsh::app::register_validate_commands(app, invocation);
  sflsh::app::register_groundtruth_commands(app, invocation);
  sflsh::app::register_metrics_commands(app, invocation);
  sflsh::app::register_render_commands(app, invocation);

  app.parse_complete_callback(
      [&] { sflsh::logger()->set_level(quiet ? spdlog::level::warn : spdlog::level::from_str(log_level)); });

  try {
    app.parse(own_argc, own_argv.data());
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // A command line that cannot be used: one line, like every other refusal, and the usage-error status 2.
    std::cerr << "sflsh: error: " << e.what() << " (see --help)" << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "sflsh: error: " << e.what() << std::endl;
    abort_other_ranks_if_parallel();
  }
  return 0;
}
