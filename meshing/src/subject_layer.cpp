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
// The most prism layers a layered fallback uses: the fine preset's 8 keep every subject valid up to h = 0.9, 16
// leaves room for shapes beyond the named subjects (~400 k tets on the open body).
constexpr int kMaxFallbackLayers = 16;

/// One fallback layer: a mesh built with `options` on the subject's shaped body (`on_subject`) or on the body itself.
struct Fallback {
  std::string label;
  LayerMeshOptions options;
  bool on_subject = false;
};

/// The fallbacks in the order tried. With cgal or gmsh, the subject's own layer by the same mesher: first at the
/// field's mean (to 0.05, so that nearby fields share a cache entry: the retarget then changes the thickness only
/// locally), then at the template's thickness (what the mesher is tuned for). Then, for every mesher, the layered
/// mesh with more prism layers than the size preset's: its nodes all sit on the subject's columns, so the template
/// retargeted is exactly the subject's own layer, and thinner prisms twist less where columns converge (a thick
/// layer at the crotch) and stay fuller where the layer is thin over concave skin (cgal at h = 0.1).
std::vector<Fallback> fallbacks(const LayerMeshOptions& options, const Eigen::VectorXd& thickness) {
  std::vector<Fallback> out;
  if (options.mesher != Mesher::layered) {
    const double mean = std::clamp(std::round(thickness.mean() / 0.05) * 0.05, 0.1, 0.9);
    std::vector<double> heights = {mean};
    if (std::abs(mean - options.template_thickness) > 1e-9) heights.push_back(options.template_thickness);
    for (const double h : heights) {
      LayerMeshOptions own = options;
      own.template_thickness = h;
      out.push_back(
          {fmt::format("the subject's own {} layer at h = {:.2f}", mesher_name(options.mesher), h), own, true});
    }
  }
  LayerMeshOptions layered = options;
  layered.mesher = Mesher::layered;
  layered.layers = 0;
  layered.template_thickness = 0.5;
  const int preset = layered_prism_layers(layered);
  for (int layers = options.mesher == Mesher::layered ? 2 * preset : preset; layers <= kMaxFallbackLayers;
       layers *= 2) {
    layered.layers = layers;
    out.push_back(
        {fmt::format("the layered mesh with {} prism layer{}", layers, layers == 1 ? "" : "s"), layered, false});
  }
  return out;
}

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
  const std::vector<int> region_vertices = out.mesh->region_surface.vertices;
  auto subject = std::make_unique<body::BodyModel>(subject_body(model, beta));
  std::string failures;
  logger()->info("{}; trying the subject's own layer (cached per subject or layer count and thickness)",
                 out.template_failure);
  for (const Fallback& fallback : fallbacks(options, thickness)) {
    const body::BodyModel& body = fallback.on_subject ? *subject : model;
    try {
      auto mesh = std::make_unique<LayerMesh>(cached_layer_mesh(body, fallback.options, cache_dir));
      require(mesh->region_surface.vertices == region_vertices,
              "the layer covers other skin vertices than the template's ({} against {})",
              mesh->region_surface.vertices.size(), region_vertices.size());
      auto retargeter = std::make_unique<Retargeter>(body, *mesh);
      RetargetedLayer layer = retargeter->retarget(fallback.on_subject ? body::Betas::Zero() : beta, thickness);
      require(layer.quality.min_dihedral_deg >= kMinDihedralDeg && layer.quality.max_radius_edge <= kMaxRadiusEdge,
              "slivers: min dihedral {:.2f}° and radius-edge ratio {:.0f} against the floor of a fallback layer, "
              "{}° and {:.0f}",
              layer.quality.min_dihedral_deg, layer.quality.max_radius_edge, kMinDihedralDeg, kMaxRadiusEdge);
      out.retargeter = std::move(retargeter);  // before the mesh it refers to is replaced
      out.mesh = std::move(mesh);
      if (fallback.on_subject) out.subject = std::move(subject);
      out.layer = std::move(layer);
      out.remeshed = true;
      out.fallback = fallback.label;
      logger()->info("using {} ({} tets, min dihedral {:.2f}°)", fallback.label, out.mesh->num_tets(),
                     out.layer.quality.min_dihedral_deg);
      return out;
    } catch (const Error& e) {
      failures += fmt::format("{}{}: {}", failures.empty() ? "" : "; ", fallback.label, e.what());
    }
  }
  throw_error("{} (the subject's own layer failed as well: {})", out.template_failure, failures);
}

}  // namespace sflsh::meshing
