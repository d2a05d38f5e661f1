#include <sflsh/core/error.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/reduced_terms.hpp>

#include <cmath>
#include <limits>

namespace sflsh::reduced {

namespace {

using model::kInfinity;

}  // namespace

double ReducedElasticTerm::value(const Eigen::VectorXd& q) const {
  try {
    const double energy = elastic_.energy(q);
    return std::isfinite(energy) ? energy : kInfinity;
  } catch (const Error&) {
    return kInfinity;  // a non-finite F or a Fung exponent over its cap: this state is out of reach
  }
}

bool ReducedElasticTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  return evaluates([&] { elastic_.add_gradient(q, gradient); }) && gradient.allFinite();
}

bool ReducedElasticTerm::add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const {
  return evaluates([&] { elastic_.add_hessian(q, hessian, projection_); });  // throws on a non-finite dP/dF
}

void ReducedInertiaTerm::set_step(const Eigen::VectorXd& p_tilde, double h_eff) {
  linear_ = inertia_.inertia_linear_term(p_tilde, h_eff);
  inertia_.mass_hessian(h_eff, hessian_);
}

double ReducedInertiaTerm::value(const Eigen::VectorXd& q) const { return linear_.dot(q) + 0.5 * q.dot(hessian_ * q); }

bool ReducedInertiaTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  gradient += linear_;
  gradient.noalias() += hessian_ * q;
  return gradient.allFinite();
}

bool ReducedInertiaTerm::add_hessian(const Eigen::VectorXd&, Eigen::MatrixXd& hessian) const {
  hessian += hessian_;
  return true;
}

double ReducedPotentialTerm::value(const Eigen::VectorXd& q) const {
  const double energy = potentials_.energy(q, inertia_);
  return std::isfinite(energy) ? energy : kInfinity;
}

bool ReducedPotentialTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  potentials_.add_gradient(q, inertia_, gradient);
  return gradient.allFinite();
}

bool ReducedPotentialTerm::add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const {
  potentials_.add_hessian(q, inertia_, hessian);
  return true;
}

}  // namespace sflsh::reduced
