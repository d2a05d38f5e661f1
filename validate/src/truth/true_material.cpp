#include <sflsh/model/simulation_output.hpp>
#include <sflsh/validate/true_material.hpp>

#include <cmath>

namespace sflsh::validate {

material::KappaMatrix true_kappa_field(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                       const body::Betas& beta, const material::ParameterBounds& bounds) {
  const meshing::RowMatrixX3d normals = model::vertex_normals(model.v_template, model.faces);
  const std::vector<int>& region = mesh.region_surface.vertices;
  material::KappaMatrix kappa(static_cast<Eigen::Index>(region.size()), material::kNumKappa);
  auto inside = [&](int column, double value) {
    const material::ParameterRange& r = bounds[column];
    const double margin = 0.02 * (r.max - r.min);
    return std::clamp(value, r.min + margin, r.max - margin);
  };
  for (std::size_t i = 0; i < region.size(); ++i) {
    const int v = region[i];
    const Eigen::Vector3d s = model.v_template.row(v).transpose();
    const Eigen::Vector3d offset = model.shapedirs.block(3 * v, 0, 3, body::kNumBetas) * beta;
    const double d = normals.row(v).dot(offset.transpose());
    const double h = 0.36 + 0.06 * std::sin(5.0 * s.y() + 1.0) + 4.0 * d;
    const double yt = 7000.0 * std::exp(0.35 * std::sin(4.0 * s.x() + 3.0 * s.y())) * std::exp(-25.0 * d);
    const double yn = 0.45 * yt * std::exp(0.25 * std::cos(6.0 * s.y()));
    const auto r = static_cast<Eigen::Index>(i);
    kappa(r, material::kThickness) = inside(material::kThickness, h);
    kappa(r, material::kYoungTangent) = inside(material::kYoungTangent, yt);
    kappa(r, material::kYoungNormal) = inside(material::kYoungNormal, yn);
  }
  return kappa;
}

std::string true_material_description() {
  return "d = n(s)·B(s)β [m] (outward offset of the shaped surface); "
         "h = 0.36 + 0.06 sin(5y + 1) + 4d; "
         "Y_t = 7000 Pa · exp(0.35 sin(4x + 3y)) · exp(-25d); "
         "Y_n = 0.45 Y_t exp(0.25 cos(6y)); (x, y) template position [m]; each clamped 2 % inside its range";
}

}  // namespace sflsh::validate
