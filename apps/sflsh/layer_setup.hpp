#pragma once
// What the commands that build a subject's soft-tissue layer and reduced models on it share (simulate,
// compare, tradeoff): the layer options on the command line, the reduced-model options and a wall clock. The
// settings themselves live in the libraries (model/layer_settings.hpp, reduced/reduced_settings.hpp), shared
// with the Python module.
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/layer_settings.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_settings.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace sflsh::app {

using Clock = std::chrono::steady_clock;

using model::body_layer_options;
using model::check_layer_settings;
using model::LayerSettings;
using model::load_layer_material;
using model::material_summary;
using model::region_normals;
using reduced::check_handle_counts;
using reduced::reduced_model_options;
using reduced::ReducedSettings;

/// --mesher, --material, --control-points, --cache, --density, --gravity, --stiffness-scale.
void add_layer_options(CLI::App& cmd, LayerSettings& settings);
/// --mass lumped|consistent (the commands that choose the inertia; the others keep lumped).
void add_mass_option(CLI::App& cmd, LayerSettings& settings);
/// --mesher layered|cgal|gmsh: the layer's tet mesher; `detail`, when given, is added to the help in parentheses.
void add_mesher_option(CLI::App& cmd, std::string& mesher, std::string_view detail = {});
/// --mesh coarse|default|fine: one layer resolution (`size_alias`: also the older spelling --size). `detail`, when
/// given, is added to the help in parentheses: e.g. what a command whose `mesh` stays empty when --mesh is not given
/// takes then ("preset: coarse"), or the sizes' tet counts.
void add_mesh_option(CLI::App& cmd, std::string& mesh, bool size_alias = false, std::string_view detail = {});
/// --frames, --fps, --substeps of a body run: `frames` output frames (the rest state included; 0 the motion's length
/// where a command allows it) at `fps`, each `substeps` solver steps.
void add_frame_options(CLI::App& cmd, int& frames, double& fps, int& substeps);
/// --cubature-weights, --affine.
void add_reduced_options(CLI::App& cmd, ReducedSettings& settings);

}  // namespace sflsh::app
