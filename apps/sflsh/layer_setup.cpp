#include "layer_setup.hpp"

namespace sflsh::app {

void add_layer_options(CLI::App& cmd, LayerSettings& s) {
  add_mesher_option(cmd, s.mesher);
  cmd.add_option("--material", s.material, "Material file (TOML); default: the project defaults at --control-points");
  cmd.add_option("--control-points", s.control_points, "Control points N when no --material is given");
  cmd.add_option("--cache", s.cache,
                 "Cache folder for template meshes and reduced models (default $SFLSH_CACHE or ~/.cache/sflsh)");
  cmd.add_option("--density", s.density, "Tissue density [kg/m³]");
  cmd.add_flag("--gravity", s.gravity, "Apply gravity");
  cmd.add_option("--stiffness-scale", s.stiffness_scale, "Multiply Y_t and Y_n by this factor");
}

void add_mass_option(CLI::App& cmd, LayerSettings& s) {
  cmd.add_option("--mass", s.mass,
                 "Inertia: consistent (default; ρV/20 (1 + δ_ab) per tet node pair) | lumped (the paper's; ρV/4 per "
                 "node); docs/integrators.md");
}

void add_mesher_option(CLI::App& cmd, std::string& mesher, std::string_view detail) {
  std::string help = "Layer mesher: layered | cgal | gmsh";
  if (!detail.empty()) help += " (" + std::string(detail) + ")";
  cmd.add_option("--mesher", mesher, help)->check(CLI::IsMember({"layered", "cgal", "gmsh"}))->capture_default_str();
}

void add_mesh_option(CLI::App& cmd, std::string& mesh, bool size_alias, std::string_view detail) {
  std::string help = size_alias ? "Layer resolution: coarse | default | fine (--size: older spelling)"
                                : "Layer resolution: coarse | default | fine";
  if (!detail.empty()) help += " (" + std::string(detail) + ")";
  cmd.add_option(size_alias ? "--mesh,--size" : "--mesh", mesh, help)
      ->check(CLI::IsMember({"coarse", "default", "medium", "fine"}))  // medium: default's older name
      ->capture_default_str();
}

void add_frame_options(CLI::App& cmd, int& frames, double& fps, int& substeps) {
  cmd.add_option("--frames", frames, "Number of frames, the rest state included (0: the motion's length)")
      ->capture_default_str();
  cmd.add_option("--fps", fps, "Frame rate of the output and of the motion's sampling [1/s]")->capture_default_str();
  cmd.add_option("--substeps", substeps, "Solver steps per frame (step = 1 / (fps · substeps))")->capture_default_str();
}

void add_reduced_options(CLI::App& cmd, ReducedSettings& s) {
  cmd.add_option("--cubature-weights", s.cubature_weights, "nnls (training-free force matching) | voronoi")
      ->check(CLI::IsMember({"nnls", "voronoi"}));
  cmd.add_flag("--affine", s.affine, "Affine point handles (12 coordinates each instead of 3)");
}

}  // namespace sflsh::app
