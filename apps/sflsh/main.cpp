// sflsh — shape-dependent soft-flesh avatars. Command-line entry point.
#include "commands.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/petsc_session.hpp>

#include <mpi.h>

#include <iostream>
#include <string>
#include <string_view>

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

/// The message with every echoed piece of input cut to 300 characters (issue 45): a quoted stretch ('…' or "…") or
/// a run without spaces longer than that keeps its first 300 characters, then "… (N characters)".
std::string cut_echoed_input(const std::string& message) {
  constexpr std::size_t kKeep = 300;
  auto cut = [&](std::string_view piece) {
    if (piece.size() <= kKeep) return std::string(piece);
    std::size_t keep = kKeep;
    while (keep > 0 && (static_cast<unsigned char>(piece[keep]) & 0xC0) == 0x80) --keep;  // whole UTF-8 characters
    return std::string(piece.substr(0, keep)) + "… (" + std::to_string(piece.size()) + " characters)";
  };
  std::string out;
  std::size_t i = 0;
  while (i < message.size()) {
    const char c = message[i];
    if (c == '\'' || c == '"') {
      const std::size_t close = message.find(c, i + 1);
      if (close != std::string::npos) {
        out += c;
        out += cut(std::string_view(message).substr(i + 1, close - i - 1));
        out += c;
        i = close + 1;
        continue;
      }
    }
    if (c != ' ') {
      std::size_t end = message.find_first_of(" '\"", i);
      if (end == std::string::npos) end = message.size();
      if (end == i) end = i + 1;
      out += cut(std::string_view(message).substr(i, end - i));
      i = end;
      continue;
    }
    out += c;
    ++i;
  }
  return out;
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
  sflsh::app::register_shapefit_commands(app, invocation);
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
    std::cerr << "sflsh: error: " << cut_echoed_input(e.what()) << " (see --help)" << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "sflsh: error: " << cut_echoed_input(e.what()) << std::endl;
    abort_other_ranks_if_parallel();
  }
  return 0;
}
