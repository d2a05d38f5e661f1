#include <sflsh/core/error.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/local_elastic.hpp>

#include <cmath>

namespace sflsh::reduced {

namespace {

Cubature touched_tets(const LocalBasis& local) {
  Cubature c;
  c.tets = local.tets;
  c.weights.assign(local.tets.size(), 1.0);
  c.method = "exact";
  return c;
}

}  // namespace

LocalElasticTerm::LocalElasticTerm(const model::Problem& problem, const Subspace& subspace, const LocalBasis& local)
    : tets_(touched_tets(local)), exact_(problem, subspace, tets_) {
  require(subspace.num_functions() >= local.size(), "local patch: {} local functions in a subspace of {}", local.size(),
          subspace.num_functions());
}

double LocalElasticTerm::value(const Eigen::VectorXd& q) const {
  try {
    const double e = exact_.energy(q);
    return std::isfinite(e) ? e : model::kInfinity;
  } catch (const Error&) {
    return model::kInfinity;  // out of the material's range, as ReducedElasticTerm
  }
}

bool LocalElasticTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  return evaluates([&] { exact_.add_gradient(q, gradient); }) && gradient.allFinite();
}

bool LocalElasticTerm::add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const {
  return evaluates([&] { exact_.add_hessian(q, hessian, projection_); });
}

}  // namespace sflsh::reduced
