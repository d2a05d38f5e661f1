#pragma once
// A serial stepper for tests: one step of a model::Integrator minimizes Φ = inertia + E + gravity
// (time_integrator.hpp) built from the model's terms (terms.hpp) by Newton with an Eigen sparse LDLᵀ solve on
// the free components, without PETSc. It is the full-space solver's step definition in ~100 lines, for small
// meshes and small steps only (no line search, no step rejection: a failure throws).
#include <sflsh/core/error.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <Eigen/SparseCholesky>

#include <vector>

namespace sflsh::testing {

class TermsStepper {
 public:
  /// `problem` validated, outliving the stepper; the exact elastic Hessian.
  TermsStepper(const model::Problem& problem, model::Integrator integrator, const model::State& initial)
      : problem_(problem),
        integrator_(integrator),
        subset_(model::TermSubset::whole(problem)),
        elastic_(problem, subset_),
        inertia_(problem, subset_),
        gravity_(problem, subset_),
        fixed_(problem.dirichlet.mask(problem.num_nodes())),
        state_(initial) {
    elastic_.set_projection(material::HessianProjection::kNone);
    free_index_.assign(fixed_.size(), -1);
    for (std::size_t d = 0; d < fixed_.size(); ++d)
      if (fixed_[d] == 0) free_index_[d] = num_free_++;
    model::NodeFrame frame;
    problem_.frame(state_.t, frame);
    history_ = model::history_of(state_, flat(model::posed_positions(frame, state_.x)));
    if (integrator_ == model::Integrator::newmark) history_.a = model::initial_acceleration(problem_, state_);
  }

  const model::State& state() const { return state_; }

  /// One step of h [s].
  void step(double h) {
    const double t = state_.t + h;
    model::NodeFrame frame;
    problem_.frame(t, frame);
    const model::InertiaTarget target = model::inertia_target(integrator_, history_, h);
    inertia_.set_step(frame, target);
    gravity_.set_frame(frame);
    Eigen::VectorXd x = state_.x;
    problem_.apply_dirichlet(t, x);
    for (int iteration = 0;; ++iteration) {
      require(iteration < 30, "terms stepper: Newton did not converge at t = {}", t);
      Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
      require(elastic_.add_gradient(x, g) && inertia_.add_gradient(x, g) && gravity_.add_gradient(x, g),
              "terms stepper: gradient failed at t = {}", t);
      Sink sink(problem_, free_index_);
      require(elastic_.add_hessian(x, sink) && inertia_.add_hessian(x, sink), "terms stepper: Hessian failed at t = {}",
              t);
      Eigen::VectorXd rhs(num_free_);
      for (std::size_t d = 0; d < fixed_.size(); ++d)
        if (free_index_[d] >= 0) rhs[free_index_[d]] = -g[static_cast<Eigen::Index>(d)];
      Eigen::SparseMatrix<double> H(num_free_, num_free_);
      H.setFromTriplets(sink.entries.begin(), sink.entries.end());
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
      require(solver.info() == Eigen::Success, "terms stepper: the Hessian is singular at t = {}", t);
      const Eigen::VectorXd dx = solver.solve(rhs);
      for (std::size_t d = 0; d < fixed_.size(); ++d)
        if (free_index_[d] >= 0) x[static_cast<Eigen::Index>(d)] += dx[free_index_[d]];
      if (dx.lpNorm<Eigen::Infinity>() < 1e-13) break;  // [m]: quadratic convergence, the next one is round-off
    }
    model::advance_history(target, history_, flat(model::posed_positions(frame, x)));
    state_.t = t;
    state_.x = x;
    model::store_history(history_, state_);
  }

 private:
  /// The 3×3 blocks of the Hessian on free × free components, as triplets.
  struct Sink final : model::HessianSink {
    Sink(const model::Problem& p, const std::vector<Eigen::Index>& index) : problem(p), free_index(index) {}
    void add_tet(std::size_t /*k*/, int e, const material::Matrix12d& block) override {
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) add(problem.tets(e, a), problem.tets(e, b), block.block<3, 3>(3 * a, 3 * b));
    }
    void add_node(int node, const Eigen::Matrix3d& block) override { add(node, node, block); }
    void add(int i, int j, const Eigen::Matrix3d& block) {
      for (int alpha = 0; alpha < 3; ++alpha) {
        const Eigen::Index r = free_index[static_cast<std::size_t>(3 * i + alpha)];
        if (r < 0) continue;
        for (int beta = 0; beta < 3; ++beta) {
          const Eigen::Index c = free_index[static_cast<std::size_t>(3 * j + beta)];
          if (c >= 0) entries.emplace_back(r, c, block(alpha, beta));
        }
      }
    }
    const model::Problem& problem;
    const std::vector<Eigen::Index>& free_index;
    std::vector<Eigen::Triplet<double>> entries;
  };

  static Eigen::VectorXd flat(const model::RowMatrixX3d& p) {
    return Eigen::Map<const Eigen::VectorXd>(p.data(), p.size());  // row-major N×3 → node-major 3N
  }

  const model::Problem& problem_;
  model::Integrator integrator_;
  std::shared_ptr<const model::TermSubset> subset_;
  model::ElasticTerm elastic_;
  model::InertiaTerm inertia_;
  model::GravityTerm gravity_;
  std::vector<char> fixed_;
  std::vector<Eigen::Index> free_index_;
  Eigen::Index num_free_ = 0;
  model::State state_;
  model::PosedHistory history_;
};

}  // namespace sflsh::testing
