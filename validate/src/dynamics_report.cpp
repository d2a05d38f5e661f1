#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/validate/dynamics_report.hpp>

#include <fmt/format.h>

namespace sflsh::validate {

namespace {
constexpr double kMillimetres = 1e3;
}

void write_dynamics_vtp(const std::filesystem::path& path, const RowMatrixX3d& shaped, const body::RowMatrixX3i& faces,
                        const DynamicsResult& result) {
  const Eigen::Index n = shaped.rows();
  require(result.sigma.size() == n, "{}: σ has {} values for a surface of {} vertices", path.string(),
          result.sigma.size(), n);
  Eigen::MatrixXd soft = Eigen::MatrixXd::Zero(n, 1);
  for (int v : result.soft_vertices) soft(v, 0) = 1.0;
  vtk::Fields fields;
  fields.point_data.push_back({"sigma", kMillimetres * result.sigma, false});
  fields.point_data.push_back({"sigma_normal", kMillimetres * result.sigma_normal, false});
  fields.point_data.push_back({"sigma_tangent", kMillimetres * result.sigma_tangent, false});
  fields.point_data.push_back({"soft_region", soft, true});
  const vtk::Cells triangles = faces.cast<int>();
  vtk::write_surface(path, shaped, triangles, fields);
}

void write_dynamics_csv(const std::filesystem::path& path, const DynamicsResult& result) {
  const std::vector<char> soft = result.soft_mask();
  std::string text = "vertex,sigma_mm,sigma_normal_mm,sigma_tangent_mm,soft\n";
  text.reserve(static_cast<std::size_t>(result.sigma.size()) * 40);
  for (Eigen::Index v = 0; v < result.sigma.size(); ++v)
    text += fmt::format("{},{:.6f},{:.6f},{:.6f},{}\n", v, kMillimetres * result.sigma[v],
                        kMillimetres * result.sigma_normal[v], kMillimetres * result.sigma_tangent[v],
                        soft[static_cast<std::size_t>(v)] ? 1 : 0);
  write_text_atomically(path, text);
}

nlohmann::json dynamics_summary(const DynamicsResult& result) {
  return {{"sigma_mean_soft_mm", kMillimetres * result.mean_sigma_soft()},
          {"sigma_mean_all_mm", kMillimetres * result.mean_sigma_all()},
          {"sigma_normal_mean_soft_mm", kMillimetres * result.mean_sigma_normal_soft()},
          {"sigma_tangent_mean_soft_mm", kMillimetres * result.mean_sigma_tangent_soft()},
          {"sigma_max_mm", result.sigma.size() ? kMillimetres * result.sigma.maxCoeff() : 0.0},
          {"soft_vertices", result.soft_vertices.size()},
          {"frames", result.frames}};
}

}  // namespace sflsh::validate
