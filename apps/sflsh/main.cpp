// sflsh — shape-dependent soft-flesh avatars. Command-line entry point.
#include "commands.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>

#include <iostream>

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

  const sflsh::app::Invocation invocation{argc, argv};
  sflsh::app::register_body_commands(app, invocation);
  sflsh::app::register_motion_commands(app, invocation);
  sflsh::app::register_mesh_commands(app, invocation);
  sflsh::app::register_material_commands(app, invocation);

  app.parse_complete_callback([&] {
    sflsh::logger()->set_level(quiet ? spdlog::level::warn : spdlog::level::from_str(log_level));
  });

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const sflsh::Error& e) {
    std::cerr << "sflsh: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "sflsh: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
