#pragma once
// The terms of the reduced incremental potential (model/time_integrator.hpp restricted to x = x_D + (B ⊗ I₃) q),
// each with its value [J], gradient [N] and Hessian [N/m] in the coordinates q (3S), added into dense vectors and
// 3S × 3S matrices; the solver sums the terms a step needs (reduced_solver.hpp) and builds no other:
//   ReducedElasticTerm    E(q) = Σ_c ω_c V_c Ψ(F_c(q)) by cubature (cubature_elastic.hpp); exact or PSD-projected dP/dF
//   ReducedInertiaTerm    1/(2ĥ²)(p(q) − p̃)ᵀM(p(q) − p̃) = const + c_Mᵀq + ½ qᵀ (JᵀMJ/ĥ²) q   (reduced_inertia.hpp)
//   ReducedGravityTerm    −gᵀM p(q) = const + c_gᵀ q
//   ReducedPotentialTerm  Σ_k u_k(p_{n_k}(q)) over the node potentials' candidates of the substep
//   (reduced_potentials.hpp)
// Values leave out the constants in q (the inertia and gravity terms are exactly quadratic and linear in q). A term
// reports failure as the full-space model's terms do (model/terms.hpp): +∞ for the value, false from add_gradient
// and add_hessian. The finite-difference harness in tests/reduced runs over every term.
#include <sflsh/core/error.hpp>
#include <sflsh/material/psd_projection.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>

#include <Eigen/Core>

#include <string_view>

namespace sflsh::reduced {

class ReducedTerm {
 public:
  virtual ~ReducedTerm() = default;
  virtual std::string_view name() const = 0;
  /// The value at q [J] (up to a constant); +∞ where the term refuses the state (Fung exponent over its cap).
  virtual double value(const Eigen::VectorXd& q) const = 0;
  /// Adds ∂/∂q [N] to `gradient` (3S); false when some contribution is not finite or out of the material's range.
  virtual bool add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const = 0;
  /// Adds ∂²/∂q² [N/m] to `hessian` (3S × 3S, full symmetric); false like add_gradient.
  virtual bool add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const = 0;
  /// Sets `hessian` to ∂²/∂q² (3S × 3S): what the first term of a sum does instead of adding to zeros.
  virtual bool hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const {
    hessian.setZero(q.size(), q.size());
    return add_hessian(q, hessian);
  }

 protected:
  /// Runs `add` (an evaluation that throws sflsh::Error where the material or a coupled system refuses the state)
  /// and says whether it went through: the terms' one way from a thrown refusal to the bool of add_gradient.
  template <class Add>
  static bool evaluates(Add&& add) {
    try {
      add();
      return true;
    } catch (const Error&) {
      return false;
    }
  }
};

class ReducedElasticTerm final : public ReducedTerm {
 public:
  explicit ReducedElasticTerm(const CubatureElastic& elastic) : elastic_(elastic) {}
  std::string_view name() const override { return "elastic"; }
  /// The Hessian of the next add_hessian calls: exact (kNone) or with dP/dF projected to PSD.
  void set_projection(material::HessianProjection projection) { projection_ = projection; }
  double value(const Eigen::VectorXd& q) const override;
  bool add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const override;

 private:
  const CubatureElastic& elastic_;
  material::HessianProjection projection_ = material::HessianProjection::kNone;
};

class ReducedInertiaTerm final : public ReducedTerm {
 public:
  explicit ReducedInertiaTerm(const ReducedInertia& inertia) : inertia_(inertia) {}
  std::string_view name() const override { return "inertia"; }
  /// The step: target p̃ on the inertia nodes (3 per node) and ĥ [s], at the inertia's current time. Computes c_M
  /// and JᵀMJ/ĥ² once; the evaluations then cost one 3S × 3S product.
  void set_step(const Eigen::VectorXd& p_tilde, double h_eff);
  const Eigen::MatrixXd& mass_hessian() const { return hessian_; }
  double value(const Eigen::VectorXd& q) const override;
  bool add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const override;
  bool hessian(const Eigen::VectorXd&, Eigen::MatrixXd& hessian) const override {
    hessian = hessian_;
    return true;
  }

 private:
  const ReducedInertia& inertia_;
  Eigen::VectorXd linear_;
  Eigen::MatrixXd hessian_;
};

class ReducedGravityTerm final : public ReducedTerm {
 public:
  explicit ReducedGravityTerm(const ReducedInertia& inertia) : inertia_(inertia) {}
  std::string_view name() const override { return "gravity"; }
  /// c_g at the inertia's current time (call after its set_time).
  void update() { linear_ = inertia_.gravity_linear_term(); }
  double value(const Eigen::VectorXd& q) const override { return linear_.dot(q); }
  bool add_gradient(const Eigen::VectorXd&, Eigen::VectorXd& gradient) const override {
    gradient += linear_;
    return true;
  }
  bool add_hessian(const Eigen::VectorXd&, Eigen::MatrixXd&) const override { return true; }  // linear

 private:
  const ReducedInertia& inertia_;
  Eigen::VectorXd linear_;
};

class ReducedPotentialTerm final : public ReducedTerm {
 public:
  /// The candidates are those of the potentials' last begin(); `inertia` gives the maps of the substep's end.
  ReducedPotentialTerm(const ReducedPotentials& potentials, const ReducedInertia& inertia)
      : potentials_(potentials), inertia_(inertia) {}
  std::string_view name() const override { return "potential"; }
  double value(const Eigen::VectorXd& q) const override;
  bool add_gradient(const Eigen::VectorXd& q, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& q, Eigen::MatrixXd& hessian) const override;

 private:
  const ReducedPotentials& potentials_;
  const ReducedInertia& inertia_;
};

}  // namespace sflsh::reduced
