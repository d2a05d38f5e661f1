#include <sflsh/core/error.hpp>
#include <sflsh/model/kinematics.hpp>
#include <sflsh/reduced/reduced_history.hpp>

#include <Eigen/Cholesky>

namespace sflsh::reduced {

Eigen::VectorXd gather_nodes(const Eigen::VectorXd& full, const std::vector<int>& nodes) {
  Eigen::VectorXd out(3 * static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    require(3 * nodes[a] + 2 < full.size(), "reduced: node {} outside a state of {} entries", nodes[a], full.size());
    out.segment<3>(3 * static_cast<Eigen::Index>(a)) = full.segment<3>(3 * nodes[a]);
  }
  return out;
}

void scatter_nodes(const Eigen::VectorXd& values, const std::vector<int>& nodes, Eigen::VectorXd& full) {
  require(values.size() == 3 * static_cast<Eigen::Index>(nodes.size()), "reduced: {} entries for {} nodes",
          values.size(), nodes.size());
  for (std::size_t a = 0; a < nodes.size(); ++a)
    full.segment<3>(3 * nodes[a]) = values.segment<3>(3 * static_cast<Eigen::Index>(a));
}

Eigen::VectorXd prescribed_acceleration(const model::Problem& problem, const Subspace& subspace,
                                        const Eigen::VectorXd& q, double t) {
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
  subspace.add_displacement(q, x);  // no basis function on prescribed components: they follow u(t)
  return model::kinematic_acceleration(problem, x, t);
}

Eigen::VectorXd subspace_acceleration(const ReducedInertia& inertia, const Eigen::VectorXd& elastic_gradient,
                                      const Eigen::VectorXd& zeta) {
  Eigen::MatrixXd mass;
  inertia.mass_hessian(1.0, mass);  // JᵀMJ
  require(elastic_gradient.size() == mass.rows(), "reduced: elastic gradient of {} entries for {} coordinates",
          elastic_gradient.size(), mass.rows());
  // (JᵀMJ) q̈ = −∇E + JᵀM g − JᵀM ζ, with −JᵀM g the gravity's linear term.
  const Eigen::VectorXd rhs = -elastic_gradient - inertia.gravity_linear_term() - inertia.pull_back_mass(zeta);
  const Eigen::LLT<Eigen::MatrixXd> factor(mass);
  require(factor.info() == Eigen::Success,
          "reduced: the subspace mass JᵀMJ is singular (a basis function moves no mass); no Newmark start");
  const Eigen::VectorXd a = inertia.posed_rate(factor.solve(rhs)) + zeta;
  require(a.allFinite(), "reduced: the initial acceleration is not finite at t = {} s", inertia.time());
  return a;
}

}  // namespace sflsh::reduced
