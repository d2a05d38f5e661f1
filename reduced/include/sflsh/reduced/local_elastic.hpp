#pragma once
// The elastic energy of a local patch (local_basis.hpp), exact over the tets the local functions touch. With
// q = [t; e] in the subspace [B  Φ] the body's elastic energy is
//   E(q) = E_cubature(t) + Σ_{tets T touched by Φ} V_T Ψ(F_T(q)),
// with the cubature fitted to the other tets alone (reduced_model.hpp, cubature_outside), so no tet is counted twice:
// inside the patch the body is a full-space model, outside it the reduced one. The touched tets' F depends on both
// the handles and the local coordinates; the cubature's tets have no local node, so they see the handles alone.
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/local_basis.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

class LocalElasticTerm final : public ReducedTerm {
 public:
  /// `subspace` is [B  Φ] (local_subspace()); problem and subspace must outlive the term.
  LocalElasticTerm(const model::Problem& problem, const Subspace& subspace, const LocalBasis& local);
  std::string_view name() const override { return "local"; }
  void set_projection(material::HessianProjection projection) { projection_ = projection; }
  /// x_D per node (3N), as CubatureElastic::set_prescribed_state.
  void set_prescribed_state(const Eigen::VectorXd& x_prescribed) { exact_.set_prescribed_state(x_prescribed); }
  double value(const Eigen::VectorXd& q) const override;
  bool add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const override;
  /// The patch's energy at q [J] (throws like CubatureElastic::energy).
  double energy(const Eigen::VectorXd& q) const { return exact_.energy(q); }
  int num_tets() const { return exact_.num_points(); }

 private:
  Cubature tets_;  ///< the touched tets, ω = 1
  CubatureElastic exact_;
  material::HessianProjection projection_ = material::HessianProjection::kNone;
};

}  // namespace sflsh::reduced
