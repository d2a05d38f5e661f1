#pragma once
// The one set of defaults of a body run, wherever the run is described: `sflsh simulate`, `sweep`, `compare`,
// `tradeoff`, Python's Simulation and a scene's [[body]] (docs/body_run.md, "Defaults"). The time integrator and
// the mass are model::kDefaultIntegrator and model::kDefaultMassKind (time_integrator.hpp, mass.hpp); the layer's
// material control points and density model::LayerSettings' (layer_settings.hpp).
#include <string_view>

namespace sflsh::run {

inline constexpr std::string_view kDefaultMesh = "default";  ///< layer resolution: coarse | default | fine
inline constexpr int kDefaultHandles = 86;                   ///< reduced: point handles
inline constexpr int kDefaultCubature = -1;                  ///< reduced: −1 automatic, 0 every tet, else a count
/// [m] reduced Newton's step tolerance (reduced::ReducedOptions::step_tolerance, docs/reduced.md).
inline constexpr double kDefaultNewtonTolerance = 1e-5;

}  // namespace sflsh::run
