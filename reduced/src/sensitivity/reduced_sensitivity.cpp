// Forward sensitivities of the reduced backward Euler with respect to the control points' Young moduli
// (reduced_sensitivity.hpp has the derivation; docs/reduced.md, "Sensitivities").
#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/reduced/reduced_sensitivity.hpp>
#include <sflsh/reduced/young_derivative.hpp>

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>

namespace sflsh::reduced {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

ReducedOptions sensitivity_solver_options(ReducedOptions base) {
  // ‖∇Φ‖ cannot fall much below ~1e-16 × the size of its terms (M/h² times posed positions of ~1 m: ~1e-11 N
  // on a body layer), so the absolute floor sits there; the relative and step criteria do the rest.
  base.gradient_rtol = std::min(base.gradient_rtol, 1e-12);
  base.gradient_atol = std::min(base.gradient_atol, 1e-11);
  base.step_tolerance = std::min(base.step_tolerance, 1e-12);
  base.max_newton = std::max(base.max_newton, 60);
  base.record_substeps = true;
  return base;
}

Eigen::MatrixXd solve_step_sensitivity(const Eigen::MatrixXd& hessian, const Eigen::MatrixXd& rhs, double t) {
  require(hessian.rows() == hessian.cols() && hessian.rows() == rhs.rows(),
          "sensitivity: Hessian is {}×{}, right-hand side has {} rows", hessian.rows(), hessian.cols(), rhs.rows());
  if (!hessian.allFinite()) throw_error("sensitivity: non-finite Hessian at t = {:.6f} s", t);
  if (!rhs.allFinite()) throw_error("sensitivity: non-finite right-hand side (∂∇Φ/∂Y or history) at t = {:.6f} s", t);
  const Eigen::LLT<Eigen::MatrixXd> factor(hessian);
  if (factor.info() != Eigen::Success)
    throw_error(
        "sensitivity: the exact Hessian of the step potential is not positive definite at the converged state at t = "
        "{:.6f} s: "
        "dq/dY is not defined there",
        t);
  Eigen::MatrixXd solution = factor.solve(rhs);
  if (!solution.allFinite()) throw_error("sensitivity: non-finite dq/dY at t = {:.6f} s", t);
  return solution;
}

SensitivityIntegrator::SensitivityIntegrator(const model::Problem& problem, const Subspace& subspace,
                                             const Cubature& cubature, Eigen::MatrixXd young_map,
                                             const ReducedOptions& options, const RestDirections* rest)
    : problem_(problem),
      integrator_(problem, subspace, cubature,
                  [&] {
                    ReducedOptions o = options;
                    o.record_substeps = true;
                    o.step_tolerance = std::min(o.step_tolerance, 1e-9);  // dq/dY at a converged state
                    return o;
                  }()),
      elastic_(problem, subspace, cubature),
      inertia_(problem, subspace),
      young_map_(std::move(young_map)),
      weights_(cubature.weights) {
  require(options.integrator == model::Integrator::backward_euler,
          "sensitivity: forward sensitivities are derived for backward Euler only, not for integrator '{}'",
          model::to_string(options.integrator));
  require(young_map_.rows() == cubature.size(),
          "sensitivity: the Young map has {} rows, expected one per cubature tet ({})", young_map_.rows(),
          cubature.size());
  require(young_map_.cols() >= 1 && young_map_.allFinite(), "sensitivity: the Young map must have ≥ 1 finite column");
  inertia_on_ = !options.quasi_static && problem.dynamic();
  for (int id : problem.dirichlet.drive) has_drives_ = has_drives_ || id >= 0;
  if (rest)
    rest_ = std::make_unique<RestGeometryDerivative>(problem_, subspace, elastic_, inertia_, rest->directions,
                                                     rest->depth, inertia_on_);
  sensitivity_ = Eigen::MatrixXd::Zero(subspace.num_dofs(), 2 * young_map_.cols() + (rest_ ? rest_->columns() : 0));
}

void SensitivityIntegrator::initialize(const model::State& state) {
  integrator_.initialize(state);
  sensitivity_.setZero();  // the initial state does not depend on Y (nor on X: q₀ = 0 for x = x_D)
  if (rest_) rest_->initialize(integrator_.time(), integrator_.history().p, integrator_.history().v);
  previous_.resize(0, 0);
  has_previous_ = false;
  t_current_ = integrator_.time();
  t_previous_ = t_current_;
  valid_ = true;
}

Eigen::MatrixXd SensitivityIntegrator::elastic_gradient_dyoung(const Eigen::VectorXd& q) const {
  const Eigen::Index N = young_map_.cols();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(q.size(), 2 * N);
  for (int p = 0; p < elastic_.num_points(); ++p) {
    if (elastic_.point_weight(p) == 0.0) continue;
    const material::OrthotropicFung& m = problem_.tet_material[static_cast<std::size_t>(elastic_.point_tet(p))];
    const YoungStressDerivative d = d2psi_ortho_fung_dF_dyoung(elastic_.point_deformation_gradient(p, q), m);
    for (Eigen::Index i = 0; i < N; ++i) {
      const double w = young_map_(p, i);  // ∂Y_c/∂Y_i
      if (w == 0.0) continue;
      elastic_.add_point_stress(p, d.tangent, w, out.col(i));
      elastic_.add_point_stress(p, d.normal, w, out.col(N + i));
    }
  }
  return out;
}

void SensitivityIntegrator::substep_sensitivity(const ReducedSubstep& substep, SensitivityStepStats& stats) {
  const double dt = substep.dt, t1 = substep.t0 + substep.dt;
  Eigen::VectorXd x_prescribed = Eigen::Map<const Eigen::VectorXd>(problem_.rest.data(), problem_.num_dofs());
  problem_.apply_dirichlet(t1, x_prescribed);
  inertia_.set_time(t1, x_prescribed);
  if (has_drives_) elastic_.set_prescribed_state(x_prescribed);

  // Right-hand side −(∂G/∂Y + ∂G/∂q_n S_n + ∂G/∂q_{n−1} S_{n−1}).
  auto clock = Clock::now();
  Eigen::MatrixXd rhs(substep.q.size(), sensitivity_.cols());
  rhs.leftCols(2 * young_map_.cols()) = -elastic_gradient_dyoung(substep.q);
  if (rest_) rhs.rightCols(rest_->columns()) = -rest_->gradient_derivative(substep.q, dt);
  stats.young_seconds += seconds_since(clock);
  clock = Clock::now();
  Eigen::MatrixXd hessian;
  if (inertia_on_) {
    const double r = has_previous_ ? dt / (t_current_ - t_previous_) : 0.0;  // h / h_prev
    Eigen::MatrixXd cross;
    inertia_.cross_mass(t_current_, cross);
    rhs.noalias() += ((1.0 + r) / (dt * dt)) * (cross * sensitivity_);
    if (has_previous_) {
      inertia_.cross_mass(t_previous_, cross);
      rhs.noalias() -= (r / (dt * dt)) * (cross * previous_);
    }
    stats.history_seconds += seconds_since(clock);
    clock = Clock::now();
    inertia_.mass_hessian(dt, hessian);
  } else {
    hessian.setZero(substep.q.size(), substep.q.size());
  }
  elastic_.add_hessian(substep.q, hessian, material::HessianProjection::kNone);  // exact, at the converged q
  stats.hessian_seconds += seconds_since(clock);
  clock = Clock::now();
  Eigen::MatrixXd next = solve_step_sensitivity(hessian, rhs, t1);
  stats.solve_seconds += seconds_since(clock);
  if (rest_) rest_->advance(substep.q, dt);
  previous_ = std::move(sensitivity_);
  sensitivity_ = std::move(next);
  t_previous_ = t_current_;
  t_current_ = t1;
  has_previous_ = true;
}

void SensitivityIntegrator::follow_cubature(const std::vector<double>& weights, double t) {
  if (weights == weights_) return;
  const Cubature& cubature = integrator_.cubature();
  const std::size_t known = weights_.size();
  require(weights.size() >= known && weights.size() <= cubature.tets.size(),
          "sensitivity: a substep solved with {} cubature points, {} known and {} in the solver", weights.size(), known,
          cubature.tets.size());
  if (weights.size() > known && !young_rows_)
    throw_error(
        "sensitivity: at t = {:.6f} s the guard added {} tet(s) to the cubature (tets outside it left the material's "
        "range) and the integrator has no Young-map rows for them: use a larger --cubature for this case",
        t, weights.size() - known);
  for (std::size_t p = 0; p < known; ++p)  // the donors gave up volume (reduced_solver_guard.cpp)
    if (weights[p] != weights_[p]) elastic_.set_point_weight(static_cast<int>(p), weights[p]);
  const std::vector<int> added(cubature.tets.begin() + static_cast<std::ptrdiff_t>(known),
                               cubature.tets.begin() + static_cast<std::ptrdiff_t>(weights.size()));
  for (std::size_t p = known; p < weights.size(); ++p) elastic_.add_point(cubature.tets[p], weights[p]);
  if (!added.empty()) {
    const Eigen::MatrixXd rows = young_rows_(added);
    require(
        rows.rows() == static_cast<Eigen::Index>(added.size()) && rows.cols() == young_map_.cols() && rows.allFinite(),
        "sensitivity: the Young-map rows for {} added tets are {} × {}, expected {} × {} finite", added.size(),
        rows.rows(), rows.cols(), added.size(), young_map_.cols());
    young_map_.conservativeResize(young_map_.rows() + rows.rows(), Eigen::NoChange);
    young_map_.bottomRows(rows.rows()) = rows;
    if (rest_) rest_->add_points();
  }
  weights_ = weights;
}

SensitivityStepStats SensitivityIntegrator::step_with_sensitivity(double h) {
  require(valid_, "sensitivity: the integrator is not initialized or an earlier step failed; call initialize()");
  SensitivityStepStats stats;
  stats.step = integrator_.step(h);  // on failure the state (and S) are unchanged
  const auto start = Clock::now();
  valid_ = false;
  for (const ReducedSubstep& substep : integrator_.last_substeps()) {
    follow_cubature(substep.cubature_weights, substep.t0 + substep.dt);
    substep_sensitivity(substep, stats);
    ++stats.factorizations;
  }
  valid_ = true;
  stats.seconds = seconds_since(start);
  return stats;
}

model::StepStats SensitivityIntegrator::step(double h) {
  last_ = step_with_sensitivity(h);
  return last_.step;
}

SensitivityResult simulate_with_sensitivities(const model::Problem& problem, const Subspace& subspace,
                                              const Cubature& cubature, const Eigen::MatrixXd& young_map,
                                              const model::State& start, double h, int frames,
                                              const ReducedOptions& options) {
  require(frames >= 0, "sensitivity: frame count must be ≥ 0, got {}", frames);
  const auto t0 = Clock::now();
  SensitivityIntegrator integrator(problem, subspace, cubature, young_map, options);
  integrator.initialize(start);
  SensitivityResult out;
  const auto record = [&] {
    out.t.push_back(integrator.time());
    out.q.push_back(integrator.q());
    out.dq_dyoung.push_back(integrator.dq_dyoung());
  };
  record();
  model::FrameLoopOptions loop;
  loop.frames = frames + 1;  // the start is frame 0
  loop.step = h;
  model::run_frames(integrator, loop, [&](int, double, const model::StepStats& stats) {
    out.sensitivity_seconds += integrator.last_sensitivity_stats().seconds;
    out.newton_iterations += stats.newton_iterations;
    record();
  });
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace sflsh::reduced
