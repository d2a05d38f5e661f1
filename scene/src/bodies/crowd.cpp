// A [crowd] expanded into bodies (crowd.hpp).
#include "bodies/crowd.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <algorithm>
#include <random>

namespace sflsh::scene::detail {

Crowd expand_crowd(const CrowdSpec& spec, const body::BodyModel& model, const std::filesystem::path& data_dir) {
  Crowd crowd;
  std::filesystem::path file = spec.shape_model;
  if (file.empty())
    file = data_dir.empty() ? reduced::default_shape_model_path() : data_dir / "shape_models" / "default.toml";
  crowd.shape_model = file.string();
  const reduced::ShapeModelFile shape_model = reduced::load_shape_model_file(file);
  // The crowd's layers cover the default region at the crowd's mesh preset: a model fitted elsewhere is refused.
  reduced::check_layer_match(shape_model, meshing::region_key(meshing::default_region_names()), spec.mesh,
                             "the [crowd]");
  std::mt19937_64 random(spec.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int rows = (spec.count + spec.columns - 1) / spec.columns;
  for (int i = 0; i < spec.count; ++i) {
    BodySpec b;
    b.name = fmt::format("avatar_{:02d}", i);
    b.line = spec.line;
    body::Betas beta;
    for (int k = 0; k < body::kNumBetas; ++k) beta[k] = std::clamp(spec.shape_sigma * normal(random), -3.0, 3.0);
    b.betas = std::vector<double>(beta.data(), beta.data() + beta.size());
    b.motion = spec.motion;
    b.motion_offset = spec.max_offset * uniform(random);
    const int row = i / spec.columns, column = i % spec.columns;
    b.placement.position = Eigen::Vector3d((column - 0.5 * (spec.columns - 1)) * spec.spacing, 0.0,
                                           -(row - 0.5 * (rows - 1)) * spec.spacing);
    b.solver = spec.solver;
    b.mesh = spec.mesh;
    b.handles = spec.handles;
    b.cubature = spec.cubature;
    b.integrator = spec.integrator;
    b.mass = spec.mass;
    crowd.materials.push_back(reduced::material_for_beta(shape_model, model, beta, b.name));
    crowd.bodies.push_back(std::move(b));
  }
  return crowd;
}

}  // namespace sflsh::scene::detail
