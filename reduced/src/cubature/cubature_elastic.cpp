#include <sflsh/core/error.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>

#include <algorithm>

namespace sflsh::reduced {

CubatureElastic::CubatureElastic(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature)
    : problem_(problem), subspace_(subspace) {
  require(subspace.num_nodes() == problem.num_nodes(), "cubature: subspace has {} nodes, problem {}",
          subspace.num_nodes(), problem.num_nodes());
  require(cubature.tets.size() == cubature.weights.size(), "cubature: {} tets but {} weights", cubature.tets.size(),
          cubature.weights.size());
  offset_.push_back(0);
  x_prescribed_.resize(problem.num_dofs());
  for (int i = 0; i < problem.num_nodes(); ++i) x_prescribed_.segment<3>(3 * i) = problem.rest.row(i).transpose();
  for (std::size_t p = 0; p < cubature.tets.size(); ++p) add_point(cubature.tets[p], cubature.weights[p]);
}

int CubatureElastic::add_point(int e, double weight) {
  require(e >= 0 && e < problem_.num_tets(), "cubature: tet {} out of range [0, {})", e, problem_.num_tets());
  require(std::isfinite(weight) && weight >= 0.0, "cubature: weight {} of tet {} is not non-negative", weight, e);
  const material::TetRest& rest = problem_.tet_rest[static_cast<std::size_t>(e)];
  // Shape-function gradients: g_a = row a−1 of D_m⁻¹ (a = 1..3), g_0 = −(g_1 + g_2 + g_3).
  Eigen::Matrix<double, 4, 3> g;
  g.bottomRows<3>() = rest.dm_inv;
  g.row(0) = -rest.dm_inv.colwise().sum();
  std::vector<std::pair<int, Eigen::Vector3d>> local;
  for (int a = 0; a < 4; ++a) {
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, problem_.tets(e, a)); it; ++it) {
      const int s = static_cast<int>(it.col());
      auto found = std::find_if(local.begin(), local.end(), [s](const auto& entry) { return entry.first == s; });
      const Eigen::Vector3d contribution = it.value() * g.row(a).transpose();
      if (found == local.end())
        local.emplace_back(s, contribution);
      else
        found->second += contribution;
    }
  }
  std::sort(local.begin(), local.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [s, c] : local) {
    function_.push_back(s);
    c_.push_back(c);
  }
  offset_.push_back(static_cast<int>(function_.size()));
  max_local_ = std::max(max_local_, static_cast<int>(local.size()));
  point_tet_.push_back(e);
  const double scale = problem_.tet_energy_scale.empty() ? 1.0 : problem_.tet_energy_scale[static_cast<std::size_t>(e)];
  tet_scale_.push_back(rest.volume * scale);
  point_weight_.push_back(weight * rest.volume * scale);
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = x_prescribed_.segment<3>(3 * problem_.tets(e, a));
  f_prescribed_.push_back(material::tet_deformation_gradient(rest, nodes));
  return num_points() - 1;
}

void CubatureElastic::set_point_weight(int p, double weight) {
  require(p >= 0 && p < num_points() && std::isfinite(weight) && weight >= 0.0,
          "cubature: weight {} for point {} of {}", weight, p, num_points());
  point_weight_[static_cast<std::size_t>(p)] = weight * tet_scale_[static_cast<std::size_t>(p)];
}

double CubatureElastic::point_weight_factor(int p) const {
  const double scale = tet_scale_[static_cast<std::size_t>(p)];
  return scale > 0.0 ? point_weight_[static_cast<std::size_t>(p)] / scale : 0.0;
}

void CubatureElastic::set_prescribed_state(const Eigen::VectorXd& x) {
  require(x.size() == problem_.num_dofs(), "cubature: prescribed state has {} entries, expected {}", x.size(),
          problem_.num_dofs());
  x_prescribed_ = x;
  for (std::size_t p = 0; p < point_tet_.size(); ++p) {
    const int e = point_tet_[p];
    material::TetNodes nodes;
    for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * problem_.tets(e, a));
    f_prescribed_[p] = material::tet_deformation_gradient(problem_.tet_rest[static_cast<std::size_t>(e)], nodes);
  }
}

Eigen::Matrix3d CubatureElastic::deformation_gradient(int p, const Eigen::VectorXd& q) const {
  Eigen::Matrix3d F = f_prescribed_[static_cast<std::size_t>(p)];
  for (int k = offset_[static_cast<std::size_t>(p)]; k < offset_[static_cast<std::size_t>(p) + 1]; ++k)
    F.noalias() +=
        q.segment<3>(3 * function_[static_cast<std::size_t>(k)]) * c_[static_cast<std::size_t>(k)].transpose();
  return F;
}

double CubatureElastic::energy(const Eigen::VectorXd& q) const {
  double total = 0.0;
  for (int p = 0; p < num_points(); ++p) {
    const double w = point_weight_[static_cast<std::size_t>(p)];
    if (w == 0.0) continue;
    total += w * material::psi_ortho_fung(
                     deformation_gradient(p, q),
                     problem_.tet_material[static_cast<std::size_t>(point_tet_[static_cast<std::size_t>(p)])]);
  }
  return total;
}

void CubatureElastic::add_point_gradient(int p, const Eigen::VectorXd& q, Eigen::VectorXd& gradient,
                                         double weight) const {
  const material::OrthotropicFung& m =
      problem_.tet_material[static_cast<std::size_t>(point_tet_[static_cast<std::size_t>(p)])];
  const Eigen::Matrix3d P =
      weight * point_weight_[static_cast<std::size_t>(p)] * material::dpsi_ortho_fung_dF(deformation_gradient(p, q), m);
  for (int k = offset_[static_cast<std::size_t>(p)]; k < offset_[static_cast<std::size_t>(p) + 1]; ++k)
    gradient.segment<3>(3 * function_[static_cast<std::size_t>(k)]).noalias() += P * c_[static_cast<std::size_t>(k)];
}

void CubatureElastic::add_point_stress(int p, const Eigen::Matrix3d& stress, double scale,
                                       Eigen::Ref<Eigen::VectorXd> gradient) const {
  const Eigen::Matrix3d P = scale * point_weight_[static_cast<std::size_t>(p)] * stress;
  for (int k = offset_[static_cast<std::size_t>(p)]; k < offset_[static_cast<std::size_t>(p) + 1]; ++k)
    gradient.segment<3>(3 * function_[static_cast<std::size_t>(k)]).noalias() += P * c_[static_cast<std::size_t>(k)];
}

double CubatureElastic::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  double total = 0.0;
  for (int p = 0; p < num_points(); ++p) {
    const double w = point_weight_[static_cast<std::size_t>(p)];
    if (w == 0.0) continue;
    const material::OrthotropicFung& m =
        problem_.tet_material[static_cast<std::size_t>(point_tet_[static_cast<std::size_t>(p)])];
    const material::OrthoFungValues v = material::eval_ortho_fung(deformation_gradient(p, q), m, false);
    total += w * v.psi;
    const Eigen::Matrix3d P = w * v.P;
    for (int k = offset_[static_cast<std::size_t>(p)]; k < offset_[static_cast<std::size_t>(p) + 1]; ++k)
      gradient.segment<3>(3 * function_[static_cast<std::size_t>(k)]).noalias() += P * c_[static_cast<std::size_t>(k)];
  }
  return total;
}

void CubatureElastic::add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian,
                                  material::HessianProjection projection) const {
  // Y_r(i + 3j, k) = Σ_l D(i + 3j, k + 3l) c_r(l): 9 × 3 per local function, reused for every s.
  std::vector<Eigen::Matrix<double, 9, 3>> y(static_cast<std::size_t>(max_local_));
  for (int p = 0; p < num_points(); ++p) {
    const double w = point_weight_[static_cast<std::size_t>(p)];
    if (w == 0.0) continue;
    const material::OrthotropicFung& m =
        problem_.tet_material[static_cast<std::size_t>(point_tet_[static_cast<std::size_t>(p)])];
    material::Matrix9d D = material::eval_ortho_fung(deformation_gradient(p, q), m, true).dPdF;
    if (!D.allFinite())
      throw_error("cubature point {} (tet {}): dP/dF is not finite", p, point_tet_[static_cast<std::size_t>(p)]);
    if (projection != material::HessianProjection::kNone) D = material::project_psd(D);
    D *= w;
    const int begin = offset_[static_cast<std::size_t>(p)], count = offset_[static_cast<std::size_t>(p) + 1] - begin;
    for (int r = 0; r < count; ++r) {
      const Eigen::Vector3d& c = c_[static_cast<std::size_t>(begin + r)];
      y[static_cast<std::size_t>(r)].noalias() =
          D.leftCols<3>() * c[0] + D.middleCols<3>(3) * c[1] + D.rightCols<3>() * c[2];
    }
    for (int s = 0; s < count; ++s) {
      const Eigen::Vector3d& cs = c_[static_cast<std::size_t>(begin + s)];
      const int row = 3 * function_[static_cast<std::size_t>(begin + s)];
      for (int r = s; r < count; ++r) {
        const Eigen::Matrix<double, 9, 3>& yr = y[static_cast<std::size_t>(r)];
        // block(i, k) = Σ_j c_s(j) Y_r(i + 3j, k)
        const Eigen::Matrix3d block =
            cs[0] * yr.topRows<3>() + cs[1] * yr.middleRows<3>(3) + cs[2] * yr.bottomRows<3>();
        const int col = 3 * function_[static_cast<std::size_t>(begin + r)];
        hessian.block<3, 3>(row, col) += block;
        if (r != s) hessian.block<3, 3>(col, row) += block.transpose();
      }
    }
  }
}

}  // namespace sflsh::reduced
