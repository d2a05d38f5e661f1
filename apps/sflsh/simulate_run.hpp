#pragma once
// One body along a motion with the full-space solver or the reduced model: what `sflsh simulate --solver
// full|reduced` does, shared with `sflsh sweep` (which runs many such cases in-process, `--no-output` style). The
// run itself is run::BodySimulation (run/body_simulation.hpp, shared with the Python module); this file adds
// its command-line options.
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/run/body_simulation.hpp>

#include <CLI/CLI.hpp>

#include <string>

namespace sflsh::app {

using run::BodyRunReporting;
using run::BodyRunSettings;
using run::run_body_simulation;

/// --handles, --cubature, --cubature-weights, --affine with simulate's help texts.
void add_reduced_run_options(CLI::App& cmd, BodyRunSettings& settings);
/// --integrator with simulate's help text.
void add_integrator_option(CLI::App& cmd, std::string& integrator);

}  // namespace sflsh::app
