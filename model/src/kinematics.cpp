#include <sflsh/model/kinematics.hpp>

namespace sflsh::model {

Eigen::VectorXd kinematic_velocity(const Problem& problem, const Eigen::VectorXd& x_in, double t) {
  const int n = problem.num_nodes();
  Eigen::VectorXd x = x_in;
  problem.apply_dirichlet(t, x);
  Eigen::VectorXd xdot = Eigen::VectorXd::Zero(x.size());
  const Eigen::VectorXd du = problem.dirichlet.rates(t);
  for (std::size_t k = 0; k < problem.dirichlet.dof.size(); ++k)
    xdot[problem.dirichlet.dof[k]] = du[static_cast<Eigen::Index>(k)];
  NodeFrame frame, rate;
  problem.frame(t, frame, &rate);
  Eigen::VectorXd w(x.size());
  for (int i = 0; i < n; ++i) {
    const auto si = static_cast<std::size_t>(i);
    w.segment<3>(3 * i) =
        rate.A[si] * x.segment<3>(3 * i) + rate.d.row(i).transpose() + frame.A[si] * xdot.segment<3>(3 * i);
  }
  return w;
}

Eigen::VectorXd kinematic_acceleration(const Problem& problem, const Eigen::VectorXd& x, double t) {
  constexpr double kDelta = 1e-6;  // [s]
  return (kinematic_velocity(problem, x, t + kDelta) - kinematic_velocity(problem, x, t)) / kDelta;
}

}  // namespace sflsh::model
