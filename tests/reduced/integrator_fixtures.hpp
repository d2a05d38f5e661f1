#pragma once
// Helpers for the reduced-integrator tests: a rigid swing of the whole box (node maps A(t) = R(t) ≠ I, C¹ in t), and
// a small dense full-space reference that minimizes the same incremental potential with the model's terms
// (model/terms.hpp, checked by finite differences in tests/model) and integrators (model/time_integrator.hpp),
// independent of the reduced code and of PETSc.
#include "dense_hessian.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <vector>

namespace sflsh::reduced::testing {

/// p_i = R(t)(x_i − c) + c + δ(t): a rotation by θ(t) = θ₀ sin(ωt) about `axis` through the pivot c, and a
/// translation δ(t) = δ₀ sin(ω₂t) (every node the same map).
class SwingTrajectory final : public model::NodeTrajectory {
 public:
  SwingTrajectory(int nodes, Eigen::Vector3d pivot, Eigen::Vector3d axis, double angle, double frequency,
                  Eigen::Vector3d shift, double shift_frequency)
      : nodes_(nodes),
        pivot_(pivot),
        axis_(axis.normalized()),
        angle_(angle),
        omega_(2.0 * M_PI * frequency),
        shift_(shift),
        shift_omega_(2.0 * M_PI * shift_frequency) {}
  int num_nodes() const override { return nodes_; }
  void evaluate(double t, model::NodeFrame& frame, model::NodeFrame* rate) const override {
    const double theta = angle_ * std::sin(omega_ * t), theta_rate = angle_ * omega_ * std::cos(omega_ * t);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(theta, axis_).toRotationMatrix();
    Eigen::Matrix3d K;  // [n]×
    K << 0.0, -axis_.z(), axis_.y(), axis_.z(), 0.0, -axis_.x(), -axis_.y(), axis_.x(), 0.0;
    const Eigen::Matrix3d R_rate = theta_rate * K * R;
    const Eigen::Vector3d d = pivot_ - R * pivot_ + shift_ * std::sin(shift_omega_ * t);
    const Eigen::Vector3d d_rate = -R_rate * pivot_ + shift_ * shift_omega_ * std::cos(shift_omega_ * t);
    frame.A.assign(static_cast<std::size_t>(nodes_), R);
    frame.d = d.transpose().replicate(nodes_, 1);
    if (rate) {
      rate->A.assign(static_cast<std::size_t>(nodes_), R_rate);
      rate->d = d_rate.transpose().replicate(nodes_, 1);
    }
  }

 private:
  int nodes_;
  Eigen::Vector3d pivot_, axis_;
  double angle_, omega_;
  Eigen::Vector3d shift_;
  double shift_omega_;
};

/// The full-space step of any integrator and mass by dense Newton on the free components (small meshes only):
/// Φ(x) = 1/(2ĥ²)(p − p̃)ᵀM(p − p̃) + E(x) − gᵀMp, minimized until ‖∇Φ‖ ≤ 1e-13 ‖∇Φ₀‖ (or a step below 1e-15 m),
/// from x_n with the prescribed components at t_{n+1}.
class DenseReference {
 public:
  DenseReference(const model::Problem& problem, model::Integrator integrator)
      : problem_(problem),
        integrator_(integrator),
        whole_(model::TermSubset::whole(problem)),
        elastic_(problem, whole_),
        inertia_(problem, whole_),
        gravity_(problem, whole_) {
    const std::vector<char> fixed = problem.dirichlet.mask(problem.num_nodes());
    for (int d = 0; d < problem.num_dofs(); ++d)
      if (!fixed[static_cast<std::size_t>(d)]) free_.push_back(d);
  }

  /// Newmark without accelerations takes model::initial_acceleration.
  void initialize(const model::State& start) {
    state_ = start;
    if (integrator_ == model::Integrator::newmark && state_.a.size() == 0)
      state_.a = model::initial_acceleration(problem_, state_);
    model::NodeFrame frame;
    problem_.frame(state_.t, frame);
    history_ = model::history_of(state_, posed(frame, state_.x));
  }

  void step(double h) {
    const double t1 = state_.t + h;
    model::NodeFrame frame;
    problem_.frame(t1, frame);
    Eigen::VectorXd x = state_.x;
    problem_.apply_dirichlet(t1, x);
    const model::InertiaTarget target = model::inertia_target(integrator_, history_, h);
    inertia_.set_step(frame, target);
    gravity_.set_frame(frame);
    const auto phi = [&](const Eigen::VectorXd& y) {
      return elastic_.value(y) + inertia_.value(y) + gravity_.value(y);
    };
    double g0 = 0.0;
    for (int it = 0; it < 200; ++it) {
      Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
      require(elastic_.add_gradient(x, g) && inertia_.add_gradient(x, g) && gravity_.add_gradient(x, g),
              "dense reference: gradient failed");
      const Eigen::VectorXd g_free = g(free_);
      if (it == 0) g0 = g_free.norm();
      if (g_free.norm() <= 1e-13 * g0 || g_free.norm() == 0.0) break;
      // The exact Hessian, or with dP/dF projected to PSD where the exact one is indefinite (same minimizer).
      Eigen::LLT<Eigen::MatrixXd> llt;
      for (material::HessianProjection projection :
           {material::HessianProjection::kNone, material::HessianProjection::kStressDerivative}) {
        elastic_.set_projection(projection);
        sflsh::testing::DenseHessian sink(problem_);
        require(elastic_.add_hessian(x, sink) && inertia_.add_hessian(x, sink) && gravity_.add_hessian(x, sink),
                "dense reference: Hessian failed");
        llt.compute(sink.H(free_, free_));
        if (llt.info() == Eigen::Success) break;
      }
      require(llt.info() == Eigen::Success, "dense reference: indefinite Hessian at t = {}", t1);
      const Eigen::VectorXd delta = -llt.solve(g_free);
      const double phi0 = phi(x), slope = g_free.dot(delta);
      double alpha = 1.0;
      for (int ls = 0; ls < 40; ++ls, alpha *= 0.5) {
        Eigen::VectorXd trial = x;
        trial(free_) += alpha * delta;
        const double value = phi(trial);
        if (value <= phi0 + 1e-4 * alpha * slope || std::abs(value - phi0) <= 1e-15 * std::abs(phi0)) {
          x = trial;
          break;
        }
      }
      if (alpha * delta.cwiseAbs().maxCoeff() < 1e-15) break;
    }
    model::advance_history(target, history_, posed(frame, x));
    state_.t = t1;
    state_.x = x;
    model::store_history(history_, state_);
  }

  const model::State& state() const { return state_; }

 private:
  static Eigen::VectorXd posed(const model::NodeFrame& frame, const Eigen::VectorXd& x) {
    const model::RowMatrixX3d p = model::posed_positions(frame, x);
    return Eigen::Map<const Eigen::VectorXd>(p.data(), p.size());
  }

  const model::Problem& problem_;
  model::Integrator integrator_;
  std::shared_ptr<const model::TermSubset> whole_;
  model::ElasticTerm elastic_;
  model::InertiaTerm inertia_;
  model::GravityTerm gravity_;
  std::vector<int> free_;
  model::State state_;
  model::PosedHistory history_;
};

}  // namespace sflsh::reduced::testing
