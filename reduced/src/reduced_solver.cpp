#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/reduced_history.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>

namespace sflsh::reduced {

namespace {

using Clock = std::chrono::steady_clock;
using model::kInfinity;

/// A term of the substep and the StepStats timer its evaluations count towards.
struct TimedTerm {
  const ReducedTerm* term = nullptr;
  double* seconds = nullptr;
};

Eigen::VectorXd node_major(const meshing::RowMatrixX3d& rows) {
  return Eigen::Map<const Eigen::VectorXd>(rows.data(), rows.size());
}

}  // namespace

ReducedSolver::ReducedSolver(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                             const ReducedOptions& options)
    : problem_(problem),
      subspace_(subspace),
      cubature_(cubature),
      options_(options),
      elastic_(problem, subspace, cubature_),
      inertia_(problem, subspace),
      potentials_(problem, subspace, inertia_.active_nodes()),
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
  q_ = Eigen::VectorXd::Zero(subspace.num_dofs());
  if (options.root.enabled && !options.root.joints.setup.joints.empty())
    skeleton_ = SkeletonDeviation(options.root.joints.setup);
  deviation_ = Eigen::VectorXd::Zero(skeleton_.size());
  q_rate_ = Eigen::VectorXd::Zero(subspace.num_dofs() + (options.root.enabled ? skeleton_.size() : 0) +
                                  (options.coupled ? options.coupled->size() : 0));
  q_rate_previous_ = q_rate_;
  if (options.root.enabled) setup_root();
  if (options.coupled) setup_coupled();
}

Eigen::VectorXd ReducedSolver::prescribed_state(double t) const {
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(problem_.rest.data(), problem_.num_dofs());
  problem_.apply_dirichlet(t, x);
  return x;
}

Eigen::VectorXd ReducedSolver::initial_acceleration() const {
  const auto size = 3 * static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  if (options_.quasi_static || !problem_.dynamic()) return Eigen::VectorXd::Zero(size);
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(subspace_.num_dofs());
  elastic_.add_gradient(q_, gradient);
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
  const Eigen::VectorXd x_prescribed = prescribed_state(t_);
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

bool ReducedSolver::solve_substep(double t0, double dt, material::HessianProjection projection, model::StepStats& stats,
                                  std::string& reason, int& startup) {
  const double t1 = t0 + dt;
  const bool inertia_on = !options_.quasi_static && problem_.dynamic();
  auto clock = Clock::now();
  const Eigen::VectorXd x_prescribed = prescribed_state(t1);
  inertia_.set_time(t1, x_prescribed);
  const model::InertiaTarget target = model::inertia_target(options_.integrator, history_, dt);
  const bool track = tracking();
  const auto offset = static_cast<Eigen::Index>(subspace_.num_dofs());
  model::InertiaTarget carried_target;
  meshing::RowMatrixX3d carried_end;
  DeviationPose pose;
  if (track) {  // the skeleton's inertia over every node, its tracking springs and dampers
    carried_posed(t1, x_prescribed, carried_end);
    pose = deviation_pose(t1, carried_end);
    carried_target = model::inertia_target(options_.integrator, carried_history_, dt);
    root_inertia_term_->set_step(target.p_tilde, carried_target.p_tilde, carried_end, pose, target.h_eff);
    root_tracking_term_->set_step(tracking_stiffness_, tracking_damping_, deviation_, dt, joint_limit_,
                                  joint_limit_stiffness_);
    root_potential_term_->set_pose(pose);
  } else if (inertia_on) {
    inertia_term_.set_step(target.p_tilde, target.h_eff);
  }
  gravity_term_.update();
  // x = [q; r] with a tracking skeleton, else q.
  Eigen::VectorXd x_start = q_;
  if (track) {
    x_start.resize(offset + skeleton_.size());
    x_start << q_, deviation_;
  }
  if (coupled_term_) {  // y = 0: the coupled system's own state at t0, after the root's coordinates
    const Eigen::VectorXd head = x_start;
    x_start.resize(head.size() + options_.coupled->size());
    x_start << head, Eigen::VectorXd::Zero(options_.coupled->size());
  }
  stats.inertia_seconds += seconds_since(clock);
  clock = Clock::now();
  if (has_drives_) {
    elastic_.set_prescribed_state(x_prescribed);
    if (guard_) guard_->set_prescribed_state(x_prescribed);
  }
  elastic_term_.set_projection(projection);
  stats.elastic_seconds += seconds_since(clock);
  bool contact = false;
  if (!potentials_.empty()) {
    clock = Clock::now();
    const auto inertia_nodes = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
    const meshing::RowMatrixX3d p_start = Eigen::Map<const meshing::RowMatrixX3d>(history_.p.data(), inertia_nodes, 3);
    if (track) {
      const DeviationFrame start_frame = skeleton_.frame(x_start, offset, pose.pivot, pose.centres, false);
      contact = potentials_.begin(t0, dt, p_start, inertia_, &start_frame);
    } else {
      contact = potentials_.begin(t0, dt, p_start, inertia_);
    }
    stats.potential_seconds += seconds_since(clock);
  }
  if (coupled_term_) {
    clock = Clock::now();
    const auto inertia_nodes = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
    const Eigen::Map<const meshing::RowMatrixX3d> p_start(history_.p.data(), inertia_nodes, 3);
    if (track) {
      const DeviationFrame start_frame = skeleton_.frame(x_start, offset, pose.pivot, pose.centres, false);
      coupled_term_->begin(t0, dt, p_start, &start_frame, pose);
    } else {
      coupled_term_->begin(t0, dt, p_start);
    }
    stats.potential_seconds += seconds_since(clock);
  }

  // Φ = Σ of the substep's terms (reduced_terms.hpp).
  std::array<TimedTerm, 6> terms_storage;
  std::size_t num_terms = 0;
  if (track) {
    terms_storage[num_terms++] = {root_inertia_term_.get(), &stats.inertia_seconds};
    terms_storage[num_terms++] = {root_tracking_term_.get(), &stats.inertia_seconds};
    terms_storage[num_terms++] = {gravity_head_.get(), &stats.inertia_seconds};
    terms_storage[num_terms++] = {elastic_head_.get(), &stats.elastic_seconds};
    if (contact) terms_storage[num_terms++] = {root_potential_term_.get(), &stats.potential_seconds};
    if (coupled_term_) terms_storage[num_terms++] = {coupled_term_.get(), &stats.potential_seconds};
  } else if (coupled_term_) {
    if (inertia_on) terms_storage[num_terms++] = {inertia_head_.get(), &stats.inertia_seconds};
    terms_storage[num_terms++] = {gravity_head_.get(), &stats.inertia_seconds};
    terms_storage[num_terms++] = {elastic_head_.get(), &stats.elastic_seconds};
    if (contact) terms_storage[num_terms++] = {potential_head_.get(), &stats.potential_seconds};
    terms_storage[num_terms++] = {coupled_term_.get(), &stats.potential_seconds};
  } else {
    if (inertia_on) terms_storage[num_terms++] = {&inertia_term_, &stats.inertia_seconds};
    terms_storage[num_terms++] = {&gravity_term_, &stats.inertia_seconds};
    terms_storage[num_terms++] = {&elastic_term_, &stats.elastic_seconds};
    if (contact) terms_storage[num_terms++] = {&potential_term_, &stats.potential_seconds};
  }
  const auto terms = std::span<const TimedTerm>(terms_storage.data(), num_terms);

  // +∞ where a term refuses the state.
  auto potential = [&](const Eigen::VectorXd& q) {
    double value = 0.0;
    for (const TimedTerm& term : terms) {
      const auto t = Clock::now();
      value += term.term->value(q);
      *term.seconds += seconds_since(t);
    }
    return std::isfinite(value) ? value : kInfinity;
  };

  // Solved again from the same start when a node potential refuses the result (penetration over its
  // tolerance: the potential stiffened itself).
  Eigen::VectorXd q;
  int enlargements = 0;
  for (int refinement = 0;;) {
    q = x_start;
    double phi = potential(q);
    if (options_.use_predictor && rate_steps_ >= 1) {
      // q_n + h q̇_n, plus ½h² q̈_n from the last two backward differences once there are two.
      Eigen::VectorXd predicted = x_start + dt * q_rate_;
      if (options_.predictor_order >= 2 && rate_steps_ >= 2 && rate_dt_ > 0.0)
        predicted += (0.5 * dt * dt / rate_dt_) * (q_rate_ - q_rate_previous_);
      const double phi_predicted = potential(predicted);
      if (phi_predicted < phi) {
        q = predicted;
        phi = phi_predicted;
      }
    }
    if (!std::isfinite(phi)) {
      reason = "the start of the step is outside the material's domain";
      return false;
    }

    Eigen::VectorXd gradient(q.size());
    Eigen::MatrixXd hessian;
    // A factor from another ĥ or projection, or any factor while contact is active (its Hessian changes with the
    // candidates), is not reused. ĥ is compared to 1e-12 relative: the ladder's substeps end on t0 + h exactly, so
    // equal steps differ in their last bits (and so do BDF2's coefficients), which must not force a new factor.
    const bool same_h = std::abs(factor_h_ - target.h_eff) <= 1e-12 * target.h_eff;
    if (!factor_valid_ || !same_h || factor_projection_ != projection || !options_.reuse_factorization || contact ||
        coupled_term_)
      factor_valid_ = false;
    bool fresh = false;  // the factor was computed at this step's current iterate
    bool refresh = !factor_valid_;
    double g0 = 0.0, g_previous = kInfinity;
    double previous_move = 0.0;  // ‖Δ‖∞ of the last full step [m]
    bool converged = false;
    for (int it = 0; it < options_.max_newton && !converged; ++it) {
      gradient.setZero();
      for (const TimedTerm& term : terms) {
        clock = Clock::now();
        try {
          term.term->add_gradient(q, gradient);
        } catch (const Error& e) {
          reason = e.what();
          return false;
        }
        *term.seconds += seconds_since(clock);
      }
      const double g = gradient.norm();
      stats.final_gradient = g;
      if (!std::isfinite(g)) {
        reason = "non-finite gradient";
        return false;
      }
      if (it == 0) g0 = g;
      if (g <= options_.gradient_atol || (it > 0 && g <= options_.gradient_rtol * g0)) {
        converged = true;
        reason = "gradient";
        break;
      }
      // A stale factor that no longer contracts the gradient fast enough is replaced.
      if (!fresh && g > options_.refresh_ratio * g_previous) refresh = true;
      g_previous = g;
      for (int attempt = 0; attempt < 2; ++attempt) {
        if (refresh) {
          for (std::size_t k = 0; k < terms.size(); ++k) {
            const TimedTerm& term = terms[k];
            clock = Clock::now();
            try {
              if (k == 0) {
                term.term->hessian(q, hessian);  // assigns (the inertia term copies its constant JᵀMJ/ĥ²)
              } else {
                term.term->add_hessian(q, hessian);
              }
            } catch (const Error& e) {
              reason = e.what();
              return false;
            }
            *term.seconds += seconds_since(clock);
          }
          clock = Clock::now();
          factor_.compute(hessian);
          stats.solve_seconds += seconds_since(clock);
          ++stats.factorizations;
          factor_valid_ = factor_.info() == Eigen::Success;
          factor_h_ = target.h_eff;
          factor_projection_ = projection;
          if (!factor_valid_) {
            reason = "indefinite Hessian";
            return false;
          }
          fresh = true;
          refresh = false;
        }
        clock = Clock::now();
        const Eigen::VectorXd delta = -factor_.solve(gradient);
        stats.solve_seconds += seconds_since(clock);
        ++stats.newton_iterations;
        if (!delta.allFinite()) {
          reason = "non-finite Newton step";
          factor_valid_ = false;
          return false;
        }
        // Backtracking on Φ (Armijo); a decrease below round-off of Φ counts as converged.
        const double slope = gradient.dot(delta);
        double alpha = 1.0;
        bool accepted = false;
        for (int ls = 0; ls < 40; ++ls, alpha *= 0.5) {
          const Eigen::VectorXd trial = q + alpha * delta;
          const double phi_trial = potential(trial);
          const bool roundoff =
              std::isfinite(phi_trial) && std::abs(phi_trial - phi) <= 1e-13 * std::max(1.0, std::abs(phi));
          if (phi_trial <= phi + 1e-4 * alpha * slope ||
              (alpha == 1.0 && roundoff && std::abs(slope) <= 1e-10 * std::max(1.0, std::abs(phi)))) {
            q = trial;
            phi = phi_trial;
            accepted = true;
            break;
          }
        }
        if (!accepted) {
          if (!fresh) {  // a stale factor may point badly: retry the iteration with a fresh Hessian
            refresh = true;
            continue;
          }
          reason = "line search failed";
          return false;
        }
        fresh = false;
        // The distance left to the minimizer, estimated from the contraction of the last two full steps:
        // ‖q_k − q*‖ ≲ ρ/(1 − ρ) ‖Δ_k‖ with ρ = ‖Δ_k‖/‖Δ_{k−1}‖ (‖Δ_k‖ itself until there are two) [m].
        const double moved = delta.cwiseAbs().maxCoeff();
        const double ratio = alpha == 1.0 && previous_move > 0.0 ? moved / previous_move : 1.0;
        const double left = ratio < 0.5 ? ratio / (1.0 - ratio) * moved : moved;
        previous_move = alpha == 1.0 ? moved : 0.0;
        if (alpha == 1.0 && left <= options_.step_tolerance) {
          converged = true;
          reason = "step";
        }
        break;
      }
    }
    if (!converged) {
      factor_valid_ = false;
      reason = fmt::format("no convergence in {} Newton iterations (‖∇Φ‖ = {:.3e})", options_.max_newton,
                           stats.final_gradient);
      return false;
    }
    if (!q.allFinite()) {
      reason = "non-finite state";
      return false;
    }
    if (guard_) {  // the tets outside the cubature: over the limit → into the cubature, and solve again
      clock = Clock::now();
      const std::vector<GuardViolation> over =
          q.size() > offset ? guard_->check(Eigen::VectorXd(q.head(offset))) : guard_->check(q);
      stats.elastic_seconds += seconds_since(clock);
      if (!over.empty()) {
        if (enlargements >= options_.max_enlargements) {
          reason = fmt::format(
              "tet {} outside the cubature still leaves the material's range (Fung exponent {:.3g} over the guard's "
              "limit: {} or {} J of energy) after {} enlargements of the cubature",
              over.front().tet, over.front().exponent, options_.guard_exponent, options_.guard_energy, enlargements);
          factor_valid_ = false;
          return false;
        }
        enlarge_cubature(over, t1);
        stats.cubature_added += static_cast<int>(over.size());
        ++enlargements;
        factor_valid_ = false;
        continue;
      }
    }
    if (!contact && !coupled_term_) break;
    clock = Clock::now();
    bool accepted = true;
    if (track && contact) {
      const DeviationFrame end_frame = skeleton_.frame(q, offset, pose.pivot, pose.centres, false);
      accepted = potentials_.accept(q, inertia_, &end_frame);
    } else if (contact) {
      accepted = potentials_.accept(q, inertia_);
    }
    if (coupled_term_) accepted = coupled_term_->accept(q) && accepted;
    stats.potential_seconds += seconds_since(clock);
    factor_valid_ = false;  // the factor holds this substep's contact Hessian
    if (accepted) break;
    const int most_refinements =
        std::max(contact ? potentials_.max_refinements() : 0, coupled_term_ ? options_.coupled->max_refinements() : 0);
    if (refinement >= most_refinements) {
      logger()->warn(
          "reduced: t = {:.6g}: contact still over its tolerance after {} refinement(s); the substep is kept", t1,
          refinement);
      break;
    }
    ++refinement;
    ++stats.potential_refinements;
  }
  clock = Clock::now();
  Eigen::VectorXd p_new;
  if (track) {  // the history holds the deviated (world) positions
    inertia_.posed(Eigen::VectorXd(q.head(offset)), p_new);
    const DeviationFrame end_frame = skeleton_.frame(q, offset, pose.pivot, pose.centres, false);
    const std::vector<int>& nodes = inertia_.inertia_nodes();
    for (Eigen::Index i = 0; i < p_new.size() / 3; ++i)
      p_new.segment<3>(3 * i) = end_frame.apply(nodes[static_cast<std::size_t>(i)], p_new.segment<3>(3 * i));
    Eigen::VectorXd carried_new(3 * carried_end.rows());
    for (Eigen::Index k = 0; k < carried_end.rows(); ++k)
      carried_new.segment<3>(3 * k) =
          end_frame.apply(carried_[static_cast<std::size_t>(k)], carried_end.row(k).transpose());
    model::advance_history(carried_target, carried_history_, carried_new);
  } else {
    inertia_.posed(Eigen::VectorXd(q.head(offset)), p_new);
  }
  if (coupled_term_) coupled_term_->commit(q);
  model::advance_history(target, history_, p_new);
  if (target.integrator != options_.integrator) ++startup;  // BDF2 started (or restarted) as backward Euler
  q_rate_previous_ = q_rate_;
  q_rate_ = (q - x_start) / dt;
  rate_dt_ = dt;
  ++rate_steps_;
  if (track) {
    deviation_ = q.segment(offset, skeleton_.size());
    pose_ = pose;
  }
  q_ = q.head(offset);
  t_ = t1;
  if (options_.record_substeps) substeps_.push_back({t0, dt, q_, cubature_.weights});
  stats.inertia_seconds += seconds_since(clock);
  return true;
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
  Eigen::VectorXd x = prescribed_state(t_);
  subspace_.add_displacement(q_, x);
  return x;
}

double ReducedSolver::elastic_energy() const { return elastic_.energy(q_); }

}  // namespace sflsh::reduced
