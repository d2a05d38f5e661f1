// One substep of the reduced solver (reduced_solver.hpp): the step's targets and terms, Newton on their sum, the
// guard of the tets outside the cubature, the contact refinements, and the commit of the new state.
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>
#include <span>

namespace sflsh::reduced {

namespace {

using Clock = std::chrono::steady_clock;
using model::kInfinity;

}  // namespace

struct ReducedSolver::Substep {
  /// A term of the substep and the StepStats timer its evaluations count towards.
  struct Term {
    const ReducedTerm* term = nullptr;
    double* seconds = nullptr;
  };
  double t0 = 0.0, dt = 0.0, t1 = 0.0;
  material::HessianProjection projection{};
  bool inertia_on = false, track = false, contact = false;
  Eigen::Index offset = 0;    ///< q's size; a tracking root's and a coupled system's unknowns follow
  Eigen::VectorXd x_storage;  ///< x_D when drives move it
  const Eigen::VectorXd* x_prescribed = nullptr;  ///< x_D at t1
  model::InertiaTarget target, carried_target;
  meshing::RowMatrixX3d carried_end;
  DeviationPose pose;
  Eigen::VectorXd x_start;  ///< x = [q; r; y] at t0 (r with a tracking skeleton, y with a coupled system)
  std::array<Term, 7> term_storage;
  std::size_t num_terms = 0;

  std::span<const Term> terms() const { return {term_storage.data(), num_terms}; }
  /// Φ = Σ of the substep's terms (reduced_terms.hpp); +∞ where a term refuses the state.
  double potential(const Eigen::VectorXd& q) const {
    double value = 0.0;
    for (const Term& term : terms()) {
      const auto t = Clock::now();
      value += term.term->value(q);
      *term.seconds += seconds_since(t);
    }
    return std::isfinite(value) ? value : kInfinity;
  }
};

bool ReducedSolver::solve_substep(double t0, double dt, material::HessianProjection projection, model::StepStats& stats,
                                  std::string& reason, int& startup) {
  Substep s;
  s.t0 = t0;
  s.dt = dt;
  s.t1 = t0 + dt;
  s.projection = projection;
  s.inertia_on = !options_.quasi_static && problem_.dynamic();
  s.track = tracking();
  s.offset = static_cast<Eigen::Index>(subspace_.num_dofs());
  set_substep_targets(s, stats);
  begin_substep_potentials(s, stats);
  collect_substep_terms(s, stats);

  // Solved again from the same start when the guard enlarged the cubature, or when a node potential refuses the
  // result (penetration over its tolerance: the potential stiffened itself).
  Eigen::VectorXd q;
  int enlargements = 0;
  for (int refinement = 0;;) {
    double phi = 0.0;
    if (!start_iterate(s, q, phi, reason) || !newton(s, q, phi, stats, reason)) return false;
    const GuardOutcome guard = check_guard(s, q, enlargements, stats, reason);
    if (guard == GuardOutcome::failed) return false;
    if (guard == GuardOutcome::enlarged) continue;
    const ContactOutcome contact = contact_settled(s, q, refinement, stats, reason);
    if (contact == ContactOutcome::failed) return false;
    if (contact == ContactOutcome::settled) break;
    ++refinement;
    ++stats.potential_refinements;
  }
  commit_substep(s, q, stats, startup);
  return true;
}

void ReducedSolver::set_substep_targets(Substep& s, model::StepStats& stats) {
  const auto clock = Clock::now();
  s.x_prescribed = &prescribed_state(s.t1, s.x_storage);
  inertia_.set_time(s.t1, *s.x_prescribed);
  s.target = model::inertia_target(options_.integrator, history_, s.dt);
  if (s.track) {  // the skeleton's inertia over every node, its tracking springs and dampers
    carried_posed(s.t1, *s.x_prescribed, s.carried_end);
    s.pose = deviation_pose(s.t1, s.carried_end);
    s.carried_target = model::inertia_target(options_.integrator, carried_history_, s.dt);
    root_inertia_term_->set_step(s.target.p_tilde, s.carried_target.p_tilde, s.carried_end, s.pose, s.target.h_eff);
    root_tracking_term_->set_step(tracking_stiffness_, tracking_damping_, deviation_, s.dt, joint_limit_,
                                  joint_limit_stiffness_);
    root_potential_term_->set_pose(s.pose);
  } else if (s.inertia_on) {
    inertia_term_.set_step(s.target.p_tilde, s.target.h_eff);
  }
  gravity_term_.update();
  // x = [q; r] with a tracking skeleton, else q.
  s.x_start = q_;
  if (s.track) {
    s.x_start.resize(s.offset + skeleton_.size());
    s.x_start << q_, deviation_;
  }
  if (coupled_term_) {  // y = 0: the coupled system's own state at t0, after the root's coordinates
    const Eigen::VectorXd head = s.x_start;
    s.x_start.resize(head.size() + options_.coupled->size());
    s.x_start << head, Eigen::VectorXd::Zero(options_.coupled->size());
  }
  stats.inertia_seconds += seconds_since(clock);
  const auto elastic_clock = Clock::now();
  if (has_drives_) {
    elastic_.set_prescribed_state(*s.x_prescribed);
    if (guard_) guard_->set_prescribed_state(*s.x_prescribed);
    if (local_term_) local_term_->set_prescribed_state(*s.x_prescribed);
  }
  elastic_term_.set_projection(s.projection);
  if (local_term_) local_term_->set_projection(s.projection);
  stats.elastic_seconds += seconds_since(elastic_clock);
}

void ReducedSolver::begin_substep_potentials(Substep& s, model::StepStats& stats) {
  const auto inertia_nodes = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  const Eigen::Map<const meshing::RowMatrixX3d> p_start(history_.p.data(), inertia_nodes, 3);
  if (!potentials_.empty()) {
    const auto clock = Clock::now();
    if (s.track) {
      const DeviationFrame start_frame = skeleton_.frame(s.x_start, s.offset, s.pose.pivot, s.pose.centres, false);
      s.contact = potentials_.begin(s.t0, s.dt, p_start, inertia_, &start_frame);
    } else {
      s.contact = potentials_.begin(s.t0, s.dt, p_start, inertia_);
    }
    stats.potential_seconds += seconds_since(clock);
  }
  if (coupled_term_) {
    const auto clock = Clock::now();
    if (s.track) {
      const DeviationFrame start_frame = skeleton_.frame(s.x_start, s.offset, s.pose.pivot, s.pose.centres, false);
      coupled_term_->begin(s.t0, s.dt, p_start, &start_frame, s.pose);
    } else {
      coupled_term_->begin(s.t0, s.dt, p_start);
    }
    stats.potential_seconds += seconds_since(clock);
  }
}

void ReducedSolver::collect_substep_terms(Substep& s, model::StepStats& stats) const {
  const auto add = [&s](const ReducedTerm* term, double* seconds) { s.term_storage[s.num_terms++] = {term, seconds}; };
  if (s.track) {
    add(root_inertia_term_.get(), &stats.inertia_seconds);
    add(root_tracking_term_.get(), &stats.inertia_seconds);
    add(gravity_head_.get(), &stats.inertia_seconds);
    add(elastic_head_.get(), &stats.elastic_seconds);
    if (local_head_) add(local_head_.get(), &stats.elastic_seconds);
    if (s.contact) add(root_potential_term_.get(), &stats.potential_seconds);
    if (coupled_term_) add(coupled_term_.get(), &stats.potential_seconds);
  } else if (coupled_term_) {
    if (s.inertia_on) add(inertia_head_.get(), &stats.inertia_seconds);
    add(gravity_head_.get(), &stats.inertia_seconds);
    add(elastic_head_.get(), &stats.elastic_seconds);
    if (local_head_) add(local_head_.get(), &stats.elastic_seconds);
    if (s.contact) add(potential_head_.get(), &stats.potential_seconds);
    add(coupled_term_.get(), &stats.potential_seconds);
  } else {
    if (s.inertia_on) add(&inertia_term_, &stats.inertia_seconds);
    add(&gravity_term_, &stats.inertia_seconds);
    if (local_term_) {
      add(elastic_head_.get(), &stats.elastic_seconds);
      add(local_term_.get(), &stats.elastic_seconds);
    } else {
      add(&elastic_term_, &stats.elastic_seconds);
    }
    if (s.contact) add(&potential_term_, &stats.potential_seconds);
  }
}

bool ReducedSolver::start_iterate(const Substep& s, Eigen::VectorXd& q, double& phi, std::string& reason) const {
  q = s.x_start;
  phi = s.potential(q);
  if (options_.use_predictor && rate_steps_ >= 1) {
    // q_n + h q̇_n, plus ½h² q̈_n from the last two backward differences once there are two.
    Eigen::VectorXd predicted = s.x_start + s.dt * q_rate_;
    if (options_.predictor_order >= 2 && rate_steps_ >= 2 && rate_dt_ > 0.0)
      predicted += (0.5 * s.dt * s.dt / rate_dt_) * (q_rate_ - q_rate_previous_);
    const double phi_predicted = s.potential(predicted);
    if (phi_predicted < phi) {
      q = predicted;
      phi = phi_predicted;
    }
  }
  if (!std::isfinite(phi)) {
    reason = "the start of the step is outside the material's domain";
    return false;
  }
  return true;
}

bool ReducedSolver::substep_gradient(const Substep& s, const Eigen::VectorXd& q, Eigen::VectorXd& gradient,
                                     std::string& reason) const {
  gradient.setZero();
  for (const Substep::Term& term : s.terms()) {
    const auto clock = Clock::now();
    const bool ok = term.term->add_gradient(q, gradient);
    *term.seconds += seconds_since(clock);
    if (!ok) {
      reason = fmt::format("the {} term's gradient is not finite or out of the material's range", term.term->name());
      return false;
    }
  }
  return true;
}

bool ReducedSolver::factorize(const Substep& s, const Eigen::VectorXd& q, Eigen::MatrixXd& hessian,
                              model::StepStats& stats, std::string& reason) {
  const std::span<const Substep::Term> terms = s.terms();
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const Substep::Term& term = terms[k];
    const auto clock = Clock::now();
    // The first term assigns (the inertia term copies its constant JᵀMJ/ĥ²), the others add.
    const bool ok = k == 0 ? term.term->hessian(q, hessian) : term.term->add_hessian(q, hessian);
    *term.seconds += seconds_since(clock);
    if (!ok) {
      reason = fmt::format("the {} term's Hessian is not finite or out of the material's range", term.term->name());
      return false;
    }
  }
  const auto clock = Clock::now();
  // A local patch's block is a mesh's (sparse): factored by the Schur complement on the other coordinates.
  factor_valid_ = local_term_ ? factor_.compute(hessian, handle_dofs(), subspace_.num_dofs() - handle_dofs())
                              : factor_.compute(hessian);
  stats.solve_seconds += seconds_since(clock);
  ++stats.factorizations;
  factor_h_ = s.target.h_eff;
  factor_projection_ = s.projection;
  if (!factor_valid_) {
    reason = "indefinite Hessian";
    return false;
  }
  return true;
}

bool ReducedSolver::newton(const Substep& s, Eigen::VectorXd& q, double phi, model::StepStats& stats,
                           std::string& reason) {
  Eigen::VectorXd gradient(q.size());
  Eigen::MatrixXd hessian;
  // A factor from another ĥ or projection, or any factor while contact is active (its Hessian changes with the
  // candidates), is not reused. ĥ is compared to 1e-12 relative: the ladder's substeps end on t0 + h exactly, so
  // equal steps differ in their last bits (and so do BDF2's coefficients), which must not force a new factor.
  const bool same_h = std::abs(factor_h_ - s.target.h_eff) <= 1e-12 * s.target.h_eff;
  if (!factor_valid_ || !same_h || factor_projection_ != s.projection || !options_.reuse_factorization || s.contact ||
      coupled_term_)
    factor_valid_ = false;
  bool fresh = false;  // the factor was computed at this step's current iterate
  bool refresh = !factor_valid_;
  double g0 = 0.0, g_previous = kInfinity;
  double previous_move = 0.0;  // ‖Δ‖∞ of the last full step [m]
  bool converged = false;
  for (int it = 0; it < options_.max_newton && !converged; ++it) {
    if (!substep_gradient(s, q, gradient, reason)) return false;
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
        if (!factorize(s, q, hessian, stats, reason)) return false;
        fresh = true;
        refresh = false;
      }
      const auto clock = Clock::now();
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
        const double phi_trial = s.potential(trial);
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
  return true;
}

ReducedSolver::GuardOutcome ReducedSolver::check_guard(const Substep& s, const Eigen::VectorXd& q, int& enlargements,
                                                       model::StepStats& stats, std::string& reason) {
  if (!guard_) return GuardOutcome::clear;
  // The tets outside the cubature: over their limit → into the cubature, and the substep solved again.
  const auto clock = Clock::now();
  const Eigen::Index handles = handle_dofs();  // the guard watches the cubature's model, on the handles alone
  const std::vector<GuardViolation> over =
      q.size() > handles ? guard_->check(Eigen::VectorXd(q.head(handles))) : guard_->check(q);
  stats.elastic_seconds += seconds_since(clock);
  if (over.empty()) return GuardOutcome::clear;
  if (enlargements >= options_.max_enlargements) {
    reason = fmt::format(
        "tet {} outside the cubature still leaves the material's range (Fung exponent {:.3g} over the guard's "
        "limit: {} or {} J of energy) after {} enlargements of the cubature",
        over.front().tet, over.front().exponent, options_.guard_exponent, options_.guard_energy, enlargements);
    factor_valid_ = false;
    return GuardOutcome::failed;
  }
  enlarge_cubature(over, s.t1);
  stats.cubature_added += static_cast<int>(over.size());
  ++enlargements;
  factor_valid_ = false;
  return GuardOutcome::enlarged;
}

ReducedSolver::ContactOutcome ReducedSolver::contact_settled(const Substep& s, const Eigen::VectorXd& q, int refinement,
                                                             model::StepStats& stats, std::string& reason) {
  if (!s.contact && !coupled_term_) return ContactOutcome::settled;
  const auto clock = Clock::now();
  bool accepted = true;
  if (s.track && s.contact) {
    const DeviationFrame end_frame = skeleton_.frame(q, s.offset, s.pose.pivot, s.pose.centres, false);
    accepted = potentials_.accept(q, inertia_, &end_frame);
  } else if (s.contact) {
    accepted = potentials_.accept(q, inertia_);
  }
  if (coupled_term_) accepted = coupled_term_->accept(q) && accepted;
  stats.potential_seconds += seconds_since(clock);
  factor_valid_ = false;  // the factor holds this substep's contact Hessian
  if (accepted) return ContactOutcome::settled;
  if (s.contact) {
    if (std::string why = potentials_.unresolved(); !why.empty()) {
      reason = std::move(why);
      return ContactOutcome::failed;
    }
  }
  const int most_refinements =
      std::max(s.contact ? potentials_.max_refinements() : 0, coupled_term_ ? options_.coupled->max_refinements() : 0);
  if (refinement >= most_refinements) {
    reason = fmt::format("contact with a free object still over its tolerance at t = {:.6g} s after {} stiffening(s)",
                         s.t1, refinement);
    return ContactOutcome::failed;
  }
  return ContactOutcome::refine;
}

void ReducedSolver::commit_substep(const Substep& s, const Eigen::VectorXd& q, model::StepStats& stats, int& startup) {
  const auto clock = Clock::now();
  Eigen::VectorXd p_new;
  inertia_.posed(Eigen::VectorXd(q.head(s.offset)), p_new);
  if (s.track) {  // the history holds the deviated (world) positions
    const DeviationFrame end_frame = skeleton_.frame(q, s.offset, s.pose.pivot, s.pose.centres, false);
    const std::vector<int>& nodes = inertia_.inertia_nodes();
    for (Eigen::Index i = 0; i < p_new.size() / 3; ++i)
      p_new.segment<3>(3 * i) = end_frame.apply(nodes[static_cast<std::size_t>(i)], p_new.segment<3>(3 * i));
    Eigen::VectorXd carried_new(3 * s.carried_end.rows());
    for (Eigen::Index k = 0; k < s.carried_end.rows(); ++k)
      carried_new.segment<3>(3 * k) =
          end_frame.apply(carried_[static_cast<std::size_t>(k)], s.carried_end.row(k).transpose());
    model::advance_history(s.carried_target, carried_history_, carried_new);
  }
  if (coupled_term_) coupled_term_->commit(q);
  model::advance_history(s.target, history_, p_new);
  if (s.target.integrator != options_.integrator) ++startup;  // BDF2 started (or restarted) as backward Euler
  q_rate_previous_ = q_rate_;
  q_rate_ = (q - s.x_start) / s.dt;
  rate_dt_ = s.dt;
  ++rate_steps_;
  if (s.track) {
    deviation_ = q.segment(s.offset, skeleton_.size());
    pose_ = s.pose;
  }
  q_ = q.head(s.offset);
  t_ = s.t1;
  if (options_.record_substeps) substeps_.push_back({s.t0, s.dt, q_, cubature_.weights});
  stats.inertia_seconds += seconds_since(clock);
}

}  // namespace sflsh::reduced
