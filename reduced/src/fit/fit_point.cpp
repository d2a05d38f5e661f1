#include <sflsh/reduced/fit_point.hpp>

namespace sflsh::reduced {

namespace {

bool same_kappa(const material::KappaMatrix& a, const material::KappaMatrix& b) {
  return a.rows() == b.rows() && a == b;
}

}  // namespace

const Eigen::VectorXd* FitPoint::sigma(const DynamicsCase* simulation, const material::KappaMatrix& kappa) const {
  for (const Target& t : targets)
    if (t.simulation == simulation && t.sigma.size() > 0 && same_kappa(t.kappa, kappa)) return &t.sigma;
  return nullptr;
}

const Eigen::VectorXd* FitPoint::terms(const DynamicsCase* simulation, const material::KappaMatrix& kappa,
                                       const LayerParameterization* parameterization, bool exact_thickness,
                                       double weight, const Eigen::VectorXd& target_sigma) const {
  for (const Target& t : targets)
    if (t.simulation == simulation && t.terms.size() > 0 && t.parameterization == parameterization &&
        t.exact_thickness == exact_thickness && t.weight == weight && same_kappa(t.kappa, kappa) &&
        t.target_sigma.size() == target_sigma.size() && t.target_sigma == target_sigma)
      return &t.terms;
  return nullptr;
}

}  // namespace sflsh::reduced
