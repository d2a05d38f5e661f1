#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/reduced_history.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>

#include <chrono>
#include <cmath>
#include <limits>

namespace sflsh::reduced {

namespace {

using Clock = std::chrono::steady_clock;
using model::kInfinity;

Eigen::VectorXd node_major(const meshing::RowMatrixX3d& rows) {
  return Eigen::Map<const Eigen::VectorXd>(rows.data(), rows.size());
}

}  // namespace

ReducedSolver::ReducedSolver(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                             const ReducedOptions& options)
    : problem_(problem),
      base_subspace_(subspace),
      local_subspace_(options.local ? local_subspace(subspace, *options.local) : Subspace{}),
      subspace_(options.local ? local_subspace_ : subspace),
      cubature_(cubature),
      options_(options),
      elastic_(problem, subspace, cubature_),
      inertia_(problem, subspace_),
      potentials_(problem, subspace_, inertia_.active_nodes()),
      elastic_term_(elastic_),
      inertia_term_(inertia_),
      gravity_term_(inertia_),
      potential_term_(potentials_, inertia_) {
  require(options.max_halvings >= 0 && options.max_newton >= 1, "reduced: max_halvings must be ≥ 0 and max_newton ≥ 1");
  if (options.guard)
    guard_ =
        std::make_unique<CubatureGuard>(problem, subspace, cubature_, options.guard_exponent, options.guard_energy);
  // Attached nodes must be attached as a whole and carry no basis functions.
  std::vector<int> constrained_axes(static_cast<std::size_t>(problem.num_nodes()), 0);
  for (int d : problem.dirichlet.dof) ++constrained_axes[static_cast<std::size_t>(d / 3)];
  for (int i = 0; i < problem.num_nodes(); ++i) {
    const int c = constrained_axes[static_cast<std::size_t>(i)];
    require(c == 0 || c == 3,
            "reduced: node {} has {} of 3 components prescribed; the reduced model attaches whole nodes only", i, c);
    if (c == 3) require(subspace.basis.row(i).nonZeros() == 0, "reduced: attached node {} has basis functions", i);
  }
  for (int id : problem.dirichlet.drive) has_drives_ = has_drives_ || id >= 0;
  if (options.local) {
    // The cubature must leave the patch's tets to it (reduced_model.hpp, cubature_outside), and the guard too.
    std::vector<char> in_patch(static_cast<std::size_t>(problem.num_tets()), 0);
    for (int e : options.local->tets) in_patch[static_cast<std::size_t>(e)] = 1;
    for (int e : cubature_.tets)
      require(!in_patch[static_cast<std::size_t>(e)],
              "reduced: cubature tet {} is in the local patch (fit the cubature without the patch's tets)", e);
    if (guard_)
      for (int e : options.local->tets) guard_->release(e);
    local_term_ = std::make_unique<LocalElasticTerm>(problem, subspace_, *options.local);
    elastic_head_ = std::make_unique<HeadTerm>(elastic_term_, handle_dofs());
    local_head_ = std::make_unique<HeadTerm>(*local_term_, subspace_.num_dofs());
  }
  rest_state_ = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
  q_ = Eigen::VectorXd::Zero(subspace_.num_dofs());
  if (options.root.enabled && !options.root.joints.setup.joints.empty())
    skeleton_ = SkeletonDeviation(options.root.joints.setup);
  deviation_ = Eigen::VectorXd::Zero(skeleton_.size());
  q_rate_ = Eigen::VectorXd::Zero(subspace_.num_dofs() + (options.root.enabled ? skeleton_.size() : 0) +
                                  (options.coupled ? options.coupled->size() : 0));
  q_rate_previous_ = q_rate_;
  if (options.root.enabled) setup_root();
  if (options.coupled) setup_coupled();
}

const Eigen::VectorXd& ReducedSolver::prescribed_state(double t, Eigen::VectorXd& storage) const {
  if (!has_drives_) return rest_state_;  // apply_dirichlet would write X + 0 on the attached nodes
  storage = rest_state_;
  problem_.apply_dirichlet(t, storage);
  return storage;
}

Eigen::VectorXd ReducedSolver::initial_acceleration() const {
  const auto size = 3 * static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  if (options_.quasi_static || !problem_.dynamic()) return Eigen::VectorXd::Zero(size);
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(subspace_.num_dofs());
  if (local_term_) {
    Eigen::VectorXd head = Eigen::VectorXd::Zero(handle_dofs());
    elastic_.add_gradient(Eigen::VectorXd(q_.head(handle_dofs())), head);
    gradient.head(handle_dofs()) = head;
    local_term_->add_gradient(q_, gradient);
  } else {
    elastic_.add_gradient(q_, gradient);
  }
  const Eigen::VectorXd zeta =
      gather_nodes(prescribed_acceleration(problem_, subspace_, q_, t_), inertia_.inertia_nodes());
  return subspace_acceleration(inertia_, gradient, zeta);
}

void ReducedSolver::initialize(const model::State& state) {
  const Eigen::Index dofs = problem_.num_dofs();
  require(state.x.size() == dofs && state.w.size() == dofs, "reduced: initial state has {} / {} entries, expected {}",
          state.x.size(), state.w.size(), dofs);
  require(state.x.allFinite() && state.w.allFinite(), "reduced: initial state is not finite");
  require(state.a.size() == 0 || state.a.size() == dofs,
          "reduced: initial state has {} accelerations, expected 0 or {}", state.a.size(), dofs);
  require(state.a.allFinite() && state.p_previous.allFinite() && state.w_previous.allFinite(),
          "reduced: the initial state's history (a, p_previous, w_previous) is not finite");
  t_ = state.t;
  substeps_.clear();
  Eigen::VectorXd storage;
  const Eigen::VectorXd& x_prescribed = prescribed_state(t_, storage);
  const Eigen::VectorXd u = state.x - x_prescribed;
  q_.setZero();
  if (u.cwiseAbs().maxCoeff() > 0.0 && subspace_.num_functions() > 0) {
    // Least squares on the nodes: (BᵀB) t = Bᵀ u per axis.
    const Eigen::SparseMatrix<double> gram = Eigen::SparseMatrix<double>(subspace_.basis.transpose()) * subspace_.basis;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(gram);
    require(ldlt.info() == Eigen::Success,
            "reduced: the basis has a function without support; cannot project the initial state");
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::VectorXd ua(problem_.num_nodes());
      for (int i = 0; i < problem_.num_nodes(); ++i) ua[i] = u[3 * i + axis];
      const Eigen::VectorXd ta = ldlt.solve(Eigen::VectorXd(subspace_.basis.transpose() * ua));
      for (int s = 0; s < subspace_.num_functions(); ++s) q_[3 * s + axis] = ta[s];
    }
  }
  q_rate_.setZero();
  q_rate_previous_.setZero();
  rate_steps_ = 0;
  deviation_.setZero();  // a state carries no deviation: the skeleton starts on its motion
  factor_valid_ = false;
  if (has_drives_) {
    elastic_.set_prescribed_state(x_prescribed);
    if (guard_) guard_->set_prescribed_state(x_prescribed);
    if (local_term_) local_term_->set_prescribed_state(x_prescribed);
  }
  inertia_.set_time(t_, x_prescribed);
  const std::vector<int>& nodes = inertia_.inertia_nodes();
  history_ = model::PosedHistory{};
  inertia_.posed(q_, history_.p);
  history_.v = gather_nodes(state.w, nodes);
  if (state.a.size() == dofs) {
    history_.a = gather_nodes(state.a, nodes);
  } else if (options_.integrator == model::Integrator::newmark) {
    history_.a = initial_acceleration();
  }
  if (state.p_previous.size() == dofs && state.w_previous.size() == dofs && state.h_previous > 0.0) {
    history_.p_previous = gather_nodes(state.p_previous, nodes);
    history_.v_previous = gather_nodes(state.w_previous, nodes);
    history_.h_previous = state.h_previous;
  }
  if (tracking()) {
    meshing::RowMatrixX3d carried;
    carried_posed(t_, x_prescribed, carried);
    carried_history_ = model::PosedHistory{};
    carried_history_.p = node_major(carried);
    carried_history_.v = gather_nodes(state.w, carried_);
    setup_tracking_springs(carried);
  }
}

model::State ReducedSolver::full_state() const {
  model::State s = model::initial_state(problem_, t_);
  subspace_.add_displacement(q_, s.x);
  const std::vector<int>& nodes = inertia_.inertia_nodes();
  scatter_nodes(history_.v, nodes, s.w);
  if (options_.integrator == model::Integrator::newmark && history_.a.size() == history_.p.size()) {
    s.a = prescribed_acceleration(problem_, subspace_, q_, t_);  // off the inertia nodes: the prescribed motion's
    scatter_nodes(history_.a, nodes, s.a);
  }
  if (options_.integrator == model::Integrator::bdf2 && history_.p_previous.size() == history_.p.size() &&
      history_.h_previous > 0.0) {
    // Off the inertia nodes x = x_D (no basis function there): the prescribed motion one step back.
    const double t_previous = t_ - history_.h_previous;
    const model::State previous = model::initial_state(problem_, t_previous);
    model::NodeFrame frame;
    problem_.frame(t_previous, frame);
    s.p_previous = node_major(model::posed_positions(frame, previous.x));
    s.w_previous = previous.w;
    scatter_nodes(history_.p_previous, nodes, s.p_previous);
    scatter_nodes(history_.v_previous, nodes, s.w_previous);
    s.h_previous = history_.h_previous;
  }
  return s;
}

Eigen::VectorXd ReducedSolver::positions() const {
  Eigen::VectorXd storage;
  Eigen::VectorXd x = prescribed_state(t_, storage);
  subspace_.add_displacement(q_, x);
  return x;
}

double ReducedSolver::elastic_energy() const {
  if (!local_term_) return elastic_.energy(q_);
  return elastic_.energy(Eigen::VectorXd(q_.head(handle_dofs()))) + local_term_->energy(q_);
}

}  // namespace sflsh::reduced
