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

void ReducedElasticTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  elastic_.add_gradient(q, gradient);
}

void ReducedElasticTerm::add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const {
  elastic_.add_hessian(q, hessian, projection_);
}

void ReducedInertiaTerm::set_step(const Eigen::VectorXd& p_tilde, double h_eff) {
  linear_ = inertia_.inertia_linear_term(p_tilde, h_eff);
  inertia_.mass_hessian(h_eff, hessian_);
}

double ReducedInertiaTerm::value(const Eigen::VectorXd& q) const { return linear_.dot(q) + 0.5 * q.dot(hessian_ * q); }

void ReducedInertiaTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  gradient += linear_;
  gradient.noalias() += hessian_ * q;
}

void ReducedInertiaTerm::add_hessian(const Eigen::VectorXd&, Eigen::MatrixXd& hessian) const { hessian += hessian_; }

double ReducedPotentialTerm::value(const Eigen::VectorXd& q) const {
  const double energy = potentials_.energy(q, inertia_);
  return std::isfinite(energy) ? energy : kInfinity;
}

}  // namespace sflsh::reduced
