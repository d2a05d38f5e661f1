#pragma once
// The elastic energy of the local bumps (local_basis.hpp), exact over the tets they touch. With q = [t; e] in the
// subspace [B  Φ] and P q = [t; 0] (the handles alone, as the cubature was fitted),
//   E(q) = E_cubature(t) + Σ_{tets T touched by Φ} V_T Ψ(F_T(q)) − V_T Ψ(F_T(P q)),
// so the model is unchanged while e = 0, and the bumps' directions carry the exact energy of the tets they strain.
// The correction's Hessian is ∇²E_T(q) − Pᵀ ∇²E_T(P q) P; with dP/dF projected (the solver's fallback) the subtracted
// part is left out, which keeps the Hessian positive semi-definite (a stiffer model of the same minimizer).
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/local_basis.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

class LocalCorrectionTerm final : public ReducedTerm {
 public:
  /// `subspace` is [B  Φ] (local_subspace()) with B's 3·`handle_dofs`/3 coordinates first; both must outlive the term.
  LocalCorrectionTerm(const model::Problem& problem, const Subspace& subspace, const LocalBasis& local,
                      Eigen::Index handle_dofs);
  std::string_view name() const override { return "local"; }
  void set_projection(material::HessianProjection projection) { projection_ = projection; }
  /// x_D per node (3N), as CubatureElastic::set_prescribed_state.
  void set_prescribed_state(const Eigen::VectorXd& x_prescribed) { exact_.set_prescribed_state(x_prescribed); }
  double value(const Eigen::VectorXd& q) const override;
  void add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const override;
  /// The correction's energy at q [J] (throws like CubatureElastic::energy).
  double energy(const Eigen::VectorXd& q) const;
  int num_tets() const { return exact_.num_points(); }

 private:
  /// q with the bumps' coordinates zeroed: the handles alone.
  Eigen::VectorXd handles_only(const Eigen::VectorXd& q) const;

  Cubature tets_;  ///< the touched tets, ω = 1
  CubatureElastic exact_;
  Eigen::Index handle_dofs_;
  material::HessianProjection projection_ = material::HessianProjection::kNone;
};

}  // namespace sflsh::reduced
