// The hidden material of the synthetic ground truth (true_material.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/meshing/correspondence.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/validate/true_material.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace sflsh::validate {

namespace {

/// FNV-1a over the bytes of the model's numbers: a shape model's identity in the ground-truth cache.
std::uint64_t digest(const reduced::ShapeModelFile& model) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](double v) {
    unsigned char bytes[sizeof v];
    std::memcpy(bytes, &v, sizeof v);
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
  };
  for (const reduced::ShapeModelControlPoint& p : model.control_points) {
    add(p.vertex);
    for (Eigen::Index k = 0; k < p.A.size(); ++k) add(p.A.data()[k]);
    for (int c = 0; c < 3; ++c) add(p.b[c]);
  }
  for (int c = 0; c < material::kNumKappa; ++c) {
    add(model.bounds[c].min);
    add(model.bounds[c].max);
  }
  return h;
}

}  // namespace

Eigen::VectorXd soft_tissue_depth_change(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                         const body::Betas& beta) {
  const Eigen::VectorXd half = Eigen::VectorXd::Constant(mesh.region_surface.num_vertices(), 0.5);
  const Eigen::VectorXd shaped =
      meshing::layer_geometry(model, mesh.region_surface, mesh.correspondence, beta, half).max_thickness();
  const Eigen::VectorXd rest =
      meshing::layer_geometry(model, mesh.region_surface, mesh.correspondence, body::Betas::Zero(), half)
          .max_thickness();
  return shaped - rest;
}

material::KappaMatrix true_kappa_field(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                       const body::Betas& beta, const material::ParameterBounds& bounds) {
  const Eigen::VectorXd depth_change = soft_tissue_depth_change(model, mesh, beta);
  const std::vector<int>& region = mesh.region_surface.vertices;
  material::KappaMatrix kappa(static_cast<Eigen::Index>(region.size()), material::kNumKappa);
  auto inside = [&](int column, double value) {
    const material::ParameterRange& r = bounds[column];
    const double margin = 0.02 * (r.max - r.min);
    return std::clamp(value, r.min + margin, r.max - margin);
  };
  for (std::size_t i = 0; i < region.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    const Eigen::Vector3d s = model.v_template.row(region[i]).transpose();
    const double d = depth_change[r];
    const double h = 0.36 + 0.06 * std::sin(5.0 * s.y() + 1.0) + kThicknessPerDepth * d;
    const double yt = 7000.0 * std::exp(0.35 * std::sin(4.0 * s.x() + 3.0 * s.y())) * std::exp(-kStiffnessPerDepth * d);
    const double yn = 0.45 * yt * std::exp(0.25 * std::cos(6.0 * s.y()));
    kappa(r, material::kThickness) = inside(material::kThickness, h);
    kappa(r, material::kYoungTangent) = inside(material::kYoungTangent, yt);
    kappa(r, material::kYoungNormal) = inside(material::kYoungNormal, yn);
  }
  return kappa;
}

TrueMaterial TrueMaterial::from_shape_model(const std::filesystem::path& path) {
  TrueMaterial t;
  t.shape_model_ = reduced::load_shape_model_file(path);
  return t;
}

material::KappaMatrix TrueMaterial::kappa_field(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                                const body::Betas& beta,
                                                const material::ParameterBounds& bounds) const {
  if (!shape_model_) return true_kappa_field(model, mesh, beta, bounds);
  const reduced::ShapeModelFile& truth = *shape_model_;
  reduced::check_layer_match(truth, mesh.region, meshing::size_preset_name(mesh.size), "the ground truth");
  const material::MaterialFile at_controls = reduced::material_for_beta(truth, model, beta, "truth");
  const material::BiharmonicBasis basis = material::layer_basis(model, mesh, truth.vertices());
  material::KappaMatrix kappa = material::evaluate_field(basis.phi, at_controls.kappa());
  int clamped = 0;
  for (Eigen::Index r = 0; r < kappa.rows(); ++r)
    for (int c = 0; c < material::kNumKappa; ++c) {
      const double v = std::clamp(kappa(r, c), bounds[c].min, bounds[c].max);
      clamped += v != kappa(r, c);
      kappa(r, c) = v;
    }
  if (clamped > 0)
    logger()->warn("{}: {} of {} true parameter values lie outside the run's bounds and were clamped into them",
                   truth.source, clamped, kappa.size());
  return kappa;
}

std::string TrueMaterial::description() const {
  if (shape_model_)
    return fmt::format(
        "shape model {} (SFLSH eq. 1 at its {} control points, carried to the region by the "
        "bounded biharmonic basis, clamped into the run's bounds)",
        shape_model_->source, shape_model_->num_controls());
  return "d = |c - s|(beta) - |c - s|(0) [m] (change of the soft-tissue depth, skin s to skeleton c, with shape); "
         "h = 0.36 + 0.06 sin(5y + 1) + 8d; "
         "Y_t = 7000 Pa · exp(0.35 sin(4x + 3y)) · exp(-60d); "
         "Y_n = 0.45 Y_t exp(0.25 cos(6y)); (x, y) template position [m]; each clamped 2 % inside its range";
}

std::string TrueMaterial::fingerprint() const {
  if (shape_model_) return fmt::format("shape_model {:016x}", digest(*shape_model_));
  return "builtin depth-change v2";
}

}  // namespace sflsh::validate
