#include <sflsh/core/error.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/local_correction.hpp>

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

LocalCorrectionTerm::LocalCorrectionTerm(const model::Problem& problem, const Subspace& subspace,
                                         const LocalBasis& local, Eigen::Index handle_dofs)
    : tets_(touched_tets(local)), exact_(problem, subspace, tets_), handle_dofs_(handle_dofs) {
  require(handle_dofs >= 0 && handle_dofs + 3 * local.size() == subspace.num_dofs(),
          "local correction: {} handle coordinates and {} bumps do not make the subspace's {} coordinates", handle_dofs,
          local.size(), subspace.num_dofs());
}

Eigen::VectorXd LocalCorrectionTerm::handles_only(const Eigen::VectorXd& q) const {
  Eigen::VectorXd p = q;
  p.tail(p.size() - handle_dofs_).setZero();
  return p;
}

double LocalCorrectionTerm::energy(const Eigen::VectorXd& q) const {
  if (q.tail(q.size() - handle_dofs_).isZero(0.0)) return 0.0;  // e = 0: the two sums are the same
  return exact_.energy(q) - exact_.energy(handles_only(q));
}

double LocalCorrectionTerm::value(const Eigen::VectorXd& q) const {
  try {
    const double e = energy(q);
    return std::isfinite(e) ? e : model::kInfinity;
  } catch (const Error&) {
    return model::kInfinity;  // out of the material's range, as ReducedElasticTerm
  }
}

void LocalCorrectionTerm::add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const {
  if (q.tail(q.size() - handle_dofs_).isZero(0.0)) {
    // ∂/∂t cancels; ∂/∂e is the bumps' exact force at the handles' state.
    Eigen::VectorXd g = Eigen::VectorXd::Zero(q.size());
    exact_.add_gradient(q, g);
    gradient.tail(q.size() - handle_dofs_) += g.tail(q.size() - handle_dofs_);
    return;
  }
  exact_.add_gradient(q, gradient);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(q.size());
  exact_.add_gradient(handles_only(q), g);
  gradient.head(handle_dofs_) -= g.head(handle_dofs_);
}

void LocalCorrectionTerm::add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const {
  exact_.add_hessian(q, hessian, projection_);
  if (projection_ != material::HessianProjection::kNone) return;  // PSD: the subtracted part is left out
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(q.size(), q.size());
  exact_.add_hessian(handles_only(q), h, projection_);
  hessian.topLeftCorner(handle_dofs_, handle_dofs_) -= h.topLeftCorner(handle_dofs_, handle_dofs_);
}

}  // namespace sflsh::reduced
