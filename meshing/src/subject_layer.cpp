#include <sflsh/body/skinning.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/subject_layer.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::meshing {

body::BodyModel subject_body(const body::BodyModel& model, const body::Betas& beta) {
  body::BodyModel subject = model;
  subject.v_template = body::shaped_template(model, beta);
  subject.name =
      (model.name.empty() ? std::string("body") : model.name) + "-shape-" + body_fingerprint(subject).substr(0, 8);
  return subject;
}

namespace {

// The floor a subject's own layer must meet to replace the template. The worst retargeted template the stability
// tests simulate (layered coarse at h = 0.6) has a smallest dihedral angle of 0.97° and a largest radius-edge ratio
// of 28; the layered mesher's own thick layers fall far below it (h = 0.8 at β = 0: 0.18° and 132, on which the
// reduced model's elastic energy grew to 40 kJ in ReducedStability.ThinAndThickLayers), cgal's stay far above
// (TEST_3 at 0.9: 3.2° and 3.8).
constexpr double kMinDihedralDeg = 0.5;
constexpr double kMaxRadiusEdge = 50.0;

}  // namespace

SubjectLayer subject_layer(const body::BodyModel& model, LayerMesh template_mesh, const body::Betas& beta,
                           const Eigen::VectorXd& thickness, const LayerMeshOptions& options,
                           const std::filesystem::path& cache_dir) {
  SubjectLayer out;
  out.mesh = std::make_unique<LayerMesh>(std::move(template_mesh));
  out.retargeter = std::make_unique<Retargeter>(model, *out.mesh);
  try {
    out.layer = out.retargeter->retarget(beta, thickness);
    return out;
  } catch (const Error& e) {
    out.template_failure = e.what();
  }
  // The subject's own layer: its shaped body meshed, retargeted at its β = 0 to the field. First at the field's mean
  // (to 0.05, so that nearby fields share a cache entry: the retarget then changes the thickness only locally), then
  // at the template's thickness (what the mesher is tuned for, where meshing at the mean fails).
  const std::vector<int> region_vertices = out.mesh->region_surface.vertices;
  const double mean = std::clamp(std::round(thickness.mean() / 0.05) * 0.05, 0.1, 0.9);
  std::vector<double> candidates = {mean};
  if (std::abs(mean - options.template_thickness) > 1e-9) candidates.push_back(options.template_thickness);
  auto subject = std::make_unique<body::BodyModel>(subject_body(model, beta));
  std::string failures;
  logger()->info("{}; meshing the subject's own layer ({} mesher, cached per subject and thickness)",
                 out.template_failure, mesher_name(options.mesher));
  for (const double h : candidates) {
    LayerMeshOptions own = options;
    own.template_thickness = h;
    try {
      auto mesh = std::make_unique<LayerMesh>(cached_layer_mesh(*subject, own, cache_dir));
      require(mesh->region_surface.vertices == region_vertices,
              "the subject's layer covers other skin vertices than the template's ({} against {})",
              mesh->region_surface.vertices.size(), region_vertices.size());
      auto retargeter = std::make_unique<Retargeter>(*subject, *mesh);
      RetargetedLayer layer = retargeter->retarget(body::Betas::Zero(), thickness);
      require(layer.quality.min_dihedral_deg >= kMinDihedralDeg && layer.quality.max_radius_edge <= kMaxRadiusEdge,
              "slivers: min dihedral {:.2f}° and radius-edge ratio {:.0f} against the floor of a fallback layer, "
              "{}° and {:.0f}",
              layer.quality.min_dihedral_deg, layer.quality.max_radius_edge, kMinDihedralDeg, kMaxRadiusEdge);
      out.retargeter = std::move(retargeter);  // before the mesh it refers to is replaced
      out.mesh = std::move(mesh);
      out.subject = std::move(subject);
      out.layer = std::move(layer);
      out.remeshed = true;
      return out;
    } catch (const Error& e) {
      failures += fmt::format("{}at h = {:.2f}: {}", failures.empty() ? "" : "; ", h, e.what());
    }
  }
  throw_error("{} (the subject's own layer failed as well: {})", out.template_failure, failures);
}

}  // namespace sflsh::meshing
