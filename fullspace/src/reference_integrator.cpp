// The SUNDIALS reference integrator (reference_integrator.hpp). Everything SUNDIALS-specific lives in this
// file and its siblings reference_integrator_impl.hpp (the shared state) and reference_integrator_mass.cpp (the
// consistent mass): SUNDIALS 6.4 as Debian 12 ships it (SUNContext_Create(nullptr, …), ARKStep*, realtype), which
// SUNDIALS 7 renames in part (SUN_COMM_NULL, ARKode* generic calls, SUNLogger instead of error handlers).
//
// Layout of y (6N): y[0, 3N) = x (node-major, 3i + axis), y[3N, 6N) = w.
// CSR pattern of J = ∂f/∂y (rows sorted, every diagonal entry present so that ARKODE's I − γJ keeps the
// pattern and KLU can refactor with the symbolic analysis of the first setup):
//   row x_{i,α}: columns x_{i,0..2}, w_{i,0..2}                          (6 entries)
//   row w_{i,α}: columns x_{j,0..2} for the mesh neighbours j of i (with i itself), then w_{i,α}
//                (consistent mass: w_{j,α} for every neighbour j, the pattern of M_w, reference_mass.hpp)
// Consistent mass: ARKODE solves M_y ẏ = f with a second KLU solver on M_y and the Newton matrix M_y − γJ
// formed by us on the fixed pattern (reference_integrator_mass.cpp).
#include "reference_integrator_impl.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace sflsh::fullspace {
namespace {

/// ARKODE's name for a return flag (the string is malloc'ed by ARKODE).
std::string flag_name(long flag) {
  char* name = ARKStepGetReturnFlagName(flag);
  std::string out = name != nullptr ? name : "unknown flag";
  std::free(name);
  return out;
}

bool all_finite(const NodeFrame& frame) {
  for (const Eigen::Matrix3d& A : frame.A) {
    if (!A.allFinite()) return false;
  }
  return frame.d.allFinite();
}

// Tolerance on ‖A − I‖_max for nodes with component-wise constraints (only meaningful for A = I).
constexpr double kIdentityTolerance = 1e-10;

}  // namespace

void ReferenceIntegrator::Impl::check(int flag, const char* call) const {
  if (flag < 0) {
    throw_error("reference integrator: {} failed with {}{}{}", call, flag_name(flag),
                last_arkode_error.empty() ? "" : ": ", last_arkode_error);
  }
}

void ReferenceIntegrator::Impl::build_pattern() {
  neighbours.assign(static_cast<std::size_t>(n), {});
  for (int i = 0; i < n; ++i) neighbours[static_cast<std::size_t>(i)].push_back(i);
  const int m = problem.num_tets();
  for (int e = 0; e < m; ++e) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b)
        neighbours[static_cast<std::size_t>(problem.tets(e, a))].push_back(problem.tets(e, b));
    }
  }
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  row_ptr.assign(static_cast<std::size_t>(2 * nx + 1), 0);
  col_idx.clear();
  for (int i = 0; i < n; ++i) {
    for (int alpha = 0; alpha < 3; ++alpha) {
      for (int b = 0; b < 3; ++b) col_idx.push_back(3 * i + b);
      for (int b = 0; b < 3; ++b) col_idx.push_back(nx + 3 * i + b);
      row_ptr[static_cast<std::size_t>(3 * i + alpha + 1)] = static_cast<sunindextype>(col_idx.size());
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int alpha = 0; alpha < 3; ++alpha) {
      for (int j : neighbours[static_cast<std::size_t>(i)]) {
        for (int b = 0; b < 3; ++b) col_idx.push_back(3 * j + b);
      }
      if (consistent) {
        for (int j : neighbours[static_cast<std::size_t>(i)]) col_idx.push_back(nx + 3 * j + alpha);
      } else {
        col_idx.push_back(nx + 3 * i + alpha);
      }
      row_ptr[static_cast<std::size_t>(nx + 3 * i + alpha + 1)] = static_cast<sunindextype>(col_idx.size());
    }
  }
  tet_block.resize(static_cast<std::size_t>(m));
  for (int e = 0; e < m; ++e) {
    for (int a = 0; a < 4; ++a) {
      const auto& list = neighbours[static_cast<std::size_t>(problem.tets(e, a))];
      for (int b = 0; b < 4; ++b) {
        const auto it = std::lower_bound(list.begin(), list.end(), problem.tets(e, b));
        tet_block[static_cast<std::size_t>(e)][static_cast<std::size_t>(4 * a + b)] =
            static_cast<int>(it - list.begin());
      }
    }
  }
  values.assign(col_idx.size(), 0.0);
}

int ReferenceIntegrator::Impl::prepare(double t_eval, const double* x) {
  // Everything here depends on t alone (the forcing), not on y: when it is not finite, smaller steps
  // cannot help (ARKODE would creep up to the bad time with ever smaller steps), so it is unrecoverable.
  try {
    problem.frame(t_eval, frame, &rate);
    x_eff = Eigen::Map<const Eigen::VectorXd>(x, nx);
    problem.apply_dirichlet(t_eval, x_eff);  // throws sflsh::Error on non-finite prescribed values
    du = problem.dirichlet.rates(t_eval);    // likewise
  } catch (const std::exception& error) {
    last_rhs_problem = error.what();
    return -1;
  }
  if (!all_finite(frame) || !all_finite(rate)) {
    last_rhs_problem = fmt::format("the node maps (trajectory) are not finite at t = {}", t_eval);
    return -1;
  }
  for (int i = 0; i < n; ++i) {
    const int count = constraint_count[static_cast<std::size_t>(i)];
    if (count > 0 && count < 3 &&
        (frame.A[static_cast<std::size_t>(i)] - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() >
            kIdentityTolerance) {
      last_rhs_problem = fmt::format(
          "node {} has {} of 3 components prescribed but its map A is not the identity at t = {} "
          "(component-wise constraints need A = I)",
          i, count, t_eval);
      return -1;
    }
  }
  return 0;
}

int ReferenceIntegrator::Impl::refusal() {
  try {
    throw;
  } catch (const Error& error) {
    // A Fung exponent beyond the cap, a non-finite F, …: the state is broken, retry with a smaller step.
    last_rhs_problem = error.what();
    return 1;
  } catch (const std::exception& error) {
    last_rhs_problem = error.what();
    return -1;
  }
}

int ReferenceIntegrator::Impl::rhs(double t_eval, const double* yv, double* ydot) {
  try {
    if (const int status = prepare(t_eval, yv); status != 0) return status;
    const ElasticEvaluation elastic = evaluate_elastic(problem, x_eff);
    if (!elastic.gradient.allFinite()) {
      last_rhs_problem = fmt::format("the elastic forces are not finite at t = {}", t_eval);
      return 1;
    }
    if (consistent) {
      if (const int status = update_coupling(t_eval); status != 0) return status;
    }
    const Eigen::Map<const Eigen::VectorXd> w(yv + nx, nx);
    Eigen::Map<Eigen::VectorXd> xdot(ydot, nx), wdot(ydot + nx, nx);
    for (int i = 0; i < n; ++i) {
      const auto si = static_cast<std::size_t>(i);
      const Eigen::Matrix3d map_inv = frame.A[si].inverse();
      const Eigen::Vector3d x_i = x_eff.segment<3>(3 * i);
      xdot.segment<3>(3 * i) = map_inv * (w.segment<3>(3 * i) - rate.A[si] * x_i - rate.d.row(i).transpose());
      const Eigen::Vector3d force = map_inv.transpose() * -elastic.gradient.segment<3>(3 * i);  // −A_i⁻ᵀ∇_i E
      if (consistent) {
        // f_w,i = −A_i⁻ᵀ∇_i E + m_i g − [M_FC a_C]_i   (the left side M_w ẇ is ARKODE's)
        wdot.segment<3>(3 * i) = force + problem.mass[i] * problem.gravity - coupling_force.segment<3>(3 * i);
      } else {
        wdot.segment<3>(3 * i) = inv_mass[si] * force + problem.gravity;  // ẇ_i = A_i⁻ᵀ(−∇_i E)/m_i + g
      }
    }
    for (std::size_t k = 0; k < problem.dirichlet.dof.size(); ++k) {
      const int dof = problem.dirichlet.dof[k];
      xdot[dof] = du[static_cast<Eigen::Index>(k)];
      wdot[dof] = 0.0;
    }
    if (!xdot.allFinite() || !wdot.allFinite()) {
      last_rhs_problem = fmt::format("the right-hand side is not finite at t = {}", t_eval);
      return 1;
    }
    return 0;
  } catch (...) {
    return refusal();
  }
}

int ReferenceIntegrator::Impl::jacobian(double t_eval, const double* yv) {
  try {
    if (const int status = prepare(t_eval, yv); status != 0) return status;
    std::fill(values.begin(), values.end(), 0.0);
    // x rows: −A⁻¹Ȧ on x_i, A⁻¹ on w_i.
    A_inv.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      const auto si = static_cast<std::size_t>(i);
      A_inv[si] = frame.A[si].inverse();
      const Eigen::Matrix3d dxdx = -A_inv[si] * rate.A[si];
      for (int alpha = 0; alpha < 3; ++alpha) {
        const auto start = static_cast<std::size_t>(row_ptr[static_cast<std::size_t>(3 * i + alpha)]);
        for (int b = 0; b < 3; ++b) {
          values[start + static_cast<std::size_t>(b)] = dxdx(alpha, b);
          values[start + 3 + static_cast<std::size_t>(b)] = A_inv[si](alpha, b);
        }
      }
    }
    // w rows: −(1/m_i) A_i⁻ᵀ K_ij.
    const int m = problem.num_tets();
    for (int e = 0; e < m; ++e) {
      const auto se = static_cast<std::size_t>(e);
      material::TetNodes nodes;
      for (int a = 0; a < 4; ++a) nodes.col(a) = x_eff.segment<3>(3 * problem.tets(e, a));
      const material::TetElastic el =
          material::tet_elastic(problem.tet_rest[se], nodes, problem.tet_material[se], true, options.projection);
      const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
      for (int a = 0; a < 4; ++a) {
        const int i = problem.tets(e, a);
        const auto si = static_cast<std::size_t>(i);
        // ∂ẇ_i/∂x_j = −(1/m_i) A_i⁻ᵀ K_ij (lumped); ∂f_w,i/∂x_j = −A_i⁻ᵀ K_ij (consistent: M_w stays on the left)
        const Eigen::Matrix3d row_map = -scale * (consistent ? 1.0 : inv_mass[si]) * A_inv[si].transpose();
        for (int b = 0; b < 4; ++b) {
          const Eigen::Matrix3d block = row_map * el.hessian.block<3, 3>(3 * a, 3 * b);
          const int k = tet_block[se][static_cast<std::size_t>(4 * a + b)];
          for (int alpha = 0; alpha < 3; ++alpha) {
            const auto start = static_cast<std::size_t>(row_ptr[static_cast<std::size_t>(nx + 3 * i + alpha)]);
            for (int beta = 0; beta < 3; ++beta)
              values[start + static_cast<std::size_t>(3 * k + beta)] += block(alpha, beta);
          }
        }
      }
    }
    // Prescribed x components: zero rows (ẋ and ẇ) and zero columns (x enters through its prescribed value).
    for (sunindextype r = 0; r < 2 * nx; ++r) {
      const bool row_fixed = constrained[static_cast<std::size_t>(r % nx)] != 0;
      for (auto q = static_cast<std::size_t>(row_ptr[static_cast<std::size_t>(r)]);
           q < static_cast<std::size_t>(row_ptr[static_cast<std::size_t>(r + 1)]); ++q) {
        const sunindextype c = col_idx[q];
        if (row_fixed || (c < nx && constrained[static_cast<std::size_t>(c)] != 0)) values[q] = 0.0;
      }
    }
    if (!std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); })) {
      last_rhs_problem = fmt::format("the Jacobian is not finite at t = {}", t_eval);
      return 1;
    }
    return 0;
  } catch (...) {
    return refusal();
  }
}

State ReferenceIntegrator::Impl::output_state(double t_out) const {
  State s;
  s.t = t_out;
  const double* yv = NV_DATA_S(y);
  s.x = Eigen::Map<const Eigen::VectorXd>(yv, nx);
  s.w = Eigen::Map<const Eigen::VectorXd>(yv + nx, nx);
  if (problem.dirichlet.dof.empty()) return s;
  // Prescribed components: their value, and the kinematic posed velocity ṗ = Ȧx + ḋ + Aẋ.
  problem.apply_dirichlet(t_out, s.x);
  const Eigen::VectorXd du_out = problem.dirichlet.rates(t_out);
  NodeFrame f, r;
  problem.frame(t_out, f, &r);
  Eigen::VectorXd xdot(nx);
  for (int i = 0; i < n; ++i) {
    const auto si = static_cast<std::size_t>(i);
    xdot.segment<3>(3 * i) =
        f.A[si].inverse() * (s.w.segment<3>(3 * i) - r.A[si] * s.x.segment<3>(3 * i) - r.d.row(i).transpose());
  }
  for (std::size_t k = 0; k < problem.dirichlet.dof.size(); ++k)
    xdot[problem.dirichlet.dof[k]] = du_out[static_cast<Eigen::Index>(k)];
  for (int dof : problem.dirichlet.dof) {
    const int i = dof / 3;
    const auto si = static_cast<std::size_t>(i);
    const Eigen::Vector3d pdot =
        r.A[si] * s.x.segment<3>(3 * i) + r.d.row(i).transpose() + f.A[si] * xdot.segment<3>(3 * i);
    s.w[dof] = pdot[dof % 3];
  }
  return s;
}

void ReferenceIntegrator::Impl::collect_stats() {
  long nfe = 0, nfi = 0;
  check(ARKStepGetNumSteps(arkode, &stats.steps), "ARKStepGetNumSteps");
  check(ARKStepGetNumRhsEvals(arkode, &nfe, &nfi), "ARKStepGetNumRhsEvals");
  stats.rhs_evals = nfe + nfi;
  check(ARKStepGetNumJacEvals(arkode, &stats.jac_evals), "ARKStepGetNumJacEvals");
  check(ARKStepGetNumNonlinSolvIters(arkode, &stats.nonlin_iters), "ARKStepGetNumNonlinSolvIters");
  check(ARKStepGetNumLinSolvSetups(arkode, &stats.lin_setups), "ARKStepGetNumLinSolvSetups");
  check(ARKStepGetNumErrTestFails(arkode, &stats.error_test_fails), "ARKStepGetNumErrTestFails");
  check(ARKStepGetNumNonlinSolvConvFails(arkode, &stats.conv_fails), "ARKStepGetNumNonlinSolvConvFails");
  stats.mass_solves = 0;
  if (consistent) check(ARKStepGetNumMassSolves(arkode, &stats.mass_solves), "ARKStepGetNumMassSolves");
  sunrealtype last = 0.0;
  check(ARKStepGetLastStep(arkode, &last), "ARKStepGetLastStep");
  stats.last_step = last;
}

ReferenceIntegrator::ReferenceIntegrator(const Problem& problem, const ReferenceOptions& options)
    : impl_(std::make_unique<Impl>(problem, options)) {
  Impl& s = *impl_;
  s.n = problem.num_nodes();
  s.nx = 3 * static_cast<sunindextype>(s.n);
  require(static_cast<int>(problem.tet_rest.size()) == problem.num_tets() &&
              static_cast<int>(problem.tet_material.size()) == problem.num_tets() && problem.mass.size() == s.n,
          "reference integrator: the problem is not validated (call Problem::validate() first)");
  require(problem.dynamic(), "reference integrator: the problem has no mass (a static problem has no dynamics)");
  require(std::isfinite(options.rtol) && options.rtol > 0.0, "reference integrator: rtol must be positive, got {}",
          options.rtol);
  require(std::isfinite(options.atol) && options.atol > 0.0, "reference integrator: atol must be positive, got {}",
          options.atol);
  require(options.max_steps > 0, "reference integrator: max_steps must be positive, got {}", options.max_steps);
  require(options.order >= 2 && options.order <= 5,
          "reference integrator: order must be in 2..5 (ARKODE's DIRK tables), got {}", options.order);
  require(std::isfinite(options.initial_step) && options.initial_step >= 0.0,
          "reference integrator: initial_step must be ≥ 0, got {}", options.initial_step);
  require(std::isfinite(options.max_step) && options.max_step >= 0.0,
          "reference integrator: max_step must be ≥ 0, got {}", options.max_step);
  require(std::isfinite(options.min_step) && options.min_step >= 0.0 &&
              (options.max_step == 0.0 || options.min_step <= options.max_step),
          "reference integrator: min_step must be in [0, max_step], got {}", options.min_step);

  s.constrained = problem.dirichlet.mask(s.n);
  s.constraint_count.assign(static_cast<std::size_t>(s.n), 0);
  for (int dof : problem.dirichlet.dof) ++s.constraint_count[static_cast<std::size_t>(dof / 3)];
  s.inv_mass.assign(static_cast<std::size_t>(s.n), 0.0);
  for (int i = 0; i < s.n; ++i) {
    const double m = problem.mass[i];
    require(m > 0.0 || s.constraint_count[static_cast<std::size_t>(i)] == 3,
            "reference integrator: node {} is not fully prescribed but has mass {} (every moving node needs mass > 0)",
            i, m);
    s.inv_mass[static_cast<std::size_t>(i)] = m > 0.0 ? 1.0 / m : 0.0;
  }
  s.consistent = problem.mass_kind == model::MassKind::consistent;
  if (s.consistent) s.check_consistent_mass();
  s.build_pattern();
  if (s.consistent) s.build_mass();

  require(SUNContext_Create(nullptr, &s.ctx) == 0 && s.ctx != nullptr,
          "reference integrator: SUNContext_Create failed");
  s.y = N_VNew_Serial(2 * s.nx, s.ctx);
  require(s.y != nullptr, "reference integrator: N_VNew_Serial({}) failed", 2 * s.nx);
  N_VConst(0.0, s.y);
  const auto nnz = static_cast<sunindextype>(s.col_idx.size());
  s.jac = SUNSparseMatrix(2 * s.nx, 2 * s.nx, nnz, CSR_MAT, s.ctx);
  require(s.jac != nullptr, "reference integrator: SUNSparseMatrix({0}×{0}, {1} nonzeros) failed", 2 * s.nx, nnz);
  std::copy(s.row_ptr.begin(), s.row_ptr.end(), SM_INDEXPTRS_S(s.jac));
  std::copy(s.col_idx.begin(), s.col_idx.end(), SM_INDEXVALS_S(s.jac));
  std::fill(SM_DATA_S(s.jac), SM_DATA_S(s.jac) + nnz, 0.0);
  s.solver = SUNLinSol_KLU(s.y, s.jac, s.ctx);
  require(s.solver != nullptr, "reference integrator: SUNLinSol_KLU failed");
  // AMD on the structurally symmetric Newton matrix I − γJ of a tet mesh: KLU's default COLAMD is meant for
  // circuit-like matrices and filled in several times more on 3D meshes.
  require(SUNLinSol_KLUSetOrdering(s.solver, 0) == SUNLS_SUCCESS, "reference integrator: KLU ordering rejected");
  if (s.consistent) s.create_mass_solver();
}

ReferenceIntegrator::~ReferenceIntegrator() = default;
ReferenceIntegrator::ReferenceIntegrator(ReferenceIntegrator&&) noexcept = default;
ReferenceIntegrator& ReferenceIntegrator::operator=(ReferenceIntegrator&&) noexcept = default;

void ReferenceIntegrator::initialize(const State& initial) {
  Impl& s = *impl_;
  require(initial.x.size() == s.nx && initial.w.size() == s.nx,
          "reference integrator: initial state has x of {} and w of {} entries, expected {}", initial.x.size(),
          initial.w.size(), s.nx);
  require(std::isfinite(initial.t) && initial.x.allFinite() && initial.w.allFinite(),
          "reference integrator: initial state is not finite");
  s.ready = false;
  s.last_arkode_error.clear();
  s.last_rhs_problem.clear();
  double* yv = NV_DATA_S(s.y);
  Eigen::Map<Eigen::VectorXd>(yv, s.nx) = initial.x;
  Eigen::Map<Eigen::VectorXd>(yv + s.nx, s.nx) = initial.w;
  if (s.arkode == nullptr) {
    s.arkode = ARKStepCreate(nullptr, &Impl::rhs_callback, initial.t, s.y, s.ctx);
    require(s.arkode != nullptr, "reference integrator: ARKStepCreate failed");
    s.check(ARKStepSetErrHandlerFn(s.arkode, &Impl::error_callback, &s), "ARKStepSetErrHandlerFn");
    s.check(ARKStepSetUserData(s.arkode, &s), "ARKStepSetUserData");
    s.check(ARKStepSStolerances(s.arkode, s.options.rtol, s.options.atol), "ARKStepSStolerances");
    s.check(ARKStepSetOrder(s.arkode, s.options.order), "ARKStepSetOrder");
    if (s.options.initial_step > 0.0)
      s.check(ARKStepSetInitStep(s.arkode, s.options.initial_step), "ARKStepSetInitStep");
    if (s.options.max_step > 0.0) s.check(ARKStepSetMaxStep(s.arkode, s.options.max_step), "ARKStepSetMaxStep");
    if (s.options.min_step > 0.0) s.check(ARKStepSetMinStep(s.arkode, s.options.min_step), "ARKStepSetMinStep");
    s.check(ARKStepSetLinearSolver(s.arkode, s.solver, s.jac), "ARKStepSetLinearSolver");
    if (s.consistent) {
      // M_y ẏ = f: M_y constant in time (SUNFALSE), factorized once per initialize by its own KLU solver.
      s.check(ARKStepSetMassLinearSolver(s.arkode, s.mass_solver, s.mass, SUNFALSE), "ARKStepSetMassLinearSolver");
      s.check(ARKStepSetMassFn(s.arkode, &Impl::mass_callback), "ARKStepSetMassFn");
      s.check(ARKStepSetLinSysFn(s.arkode, &Impl::linear_system_callback), "ARKStepSetLinSysFn");
    } else {
      s.check(ARKStepSetJacFn(s.arkode, &Impl::jacobian_callback), "ARKStepSetJacFn");
    }
  } else {
    // Keeps every option, the linear solver and the Jacobian function; resets ARKODE's counters.
    s.check(ARKStepReInit(s.arkode, nullptr, &Impl::rhs_callback, initial.t, s.y), "ARKStepReInit");
  }
  s.t = initial.t;
  s.t_start = initial.t;
  s.acceleration_time = std::numeric_limits<double>::quiet_NaN();
  s.saved_values.clear();
  s.stats = ReferenceStats{};
  s.ready = true;
}

State ReferenceIntegrator::advance_to(double t_out) {
  Impl& s = *impl_;
  require(s.ready, "reference integrator: not initialized (or a previous advance_to failed; call initialize())");
  require(std::isfinite(t_out) && t_out >= s.t, "reference integrator: cannot advance from t = {} to t = {}", s.t,
          t_out);
  if (t_out == s.t) return s.output_state(s.t);
  s.last_arkode_error.clear();
  s.last_rhs_problem.clear();
  s.check(ARKStepSetStopTime(s.arkode, t_out), "ARKStepSetStopTime");
  // One step per ARKStepEvolve call (ARK_ONE_STEP) up to the stop time: on a failure ARKODE reports the
  // time of the failing stage, while its state is that of the last accepted step, which we know this way.
  const auto start = std::chrono::steady_clock::now();
  const double seconds_before = s.stats.seconds;
  auto fail = [&](const std::string& flag, double t_failed) {
    const double seconds = seconds_since(start);
    s.ready = false;
    s.collect_stats();
    s.stats.seconds = seconds_before + seconds;
    throw_error(
        "reference integrator: ARKODE gave up at t = {} (last accepted step; failing at t = {}) on the way "
        "to t = {} with {}{}{}{}{}",
        s.t, t_failed, t_out, flag, s.last_arkode_error.empty() ? "" : ": ", s.last_arkode_error,
        s.last_rhs_problem.empty() ? "" : "; last refused right-hand side: ", s.last_rhs_problem);
  };
  for (long steps = 0;; ++steps) {
    if (steps >= s.options.max_steps) {
      fail(fmt::format("too much work ({} steps, options.max_steps)", s.options.max_steps), s.t);
    }
    sunrealtype t_reached = s.t;
    const int flag = ARKStepEvolve(s.arkode, t_out, s.y, &t_reached, ARK_ONE_STEP);
    if (flag < 0) fail(flag_name(flag), t_reached);
    s.t = t_reached;
    if (flag == ARK_TSTOP_RETURN || t_reached >= t_out) break;
  }
  const double seconds = seconds_since(start);
  s.collect_stats();
  s.stats.seconds = seconds_before + seconds;
  s.t = t_out;  // ARKODE returns exactly the stop time (interpolating across a roundoff-sized overshoot)
  return s.output_state(s.t);
}

double ReferenceIntegrator::time() const { return impl_->t; }

Eigen::VectorXd ReferenceIntegrator::rhs(double t, const Eigen::VectorXd& y) {
  Impl& s = *impl_;
  require(y.size() == 2 * s.nx, "reference integrator: rhs: y has {} entries, expected {}", y.size(), 2 * s.nx);
  Eigen::VectorXd f(y.size());
  require(s.rhs(t, y.data(), f.data()) == 0, "reference integrator: rhs failed at t = {}: {}", t, s.last_rhs_problem);
  return f;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> ReferenceIntegrator::jacobian(double t, const Eigen::VectorXd& y) {
  Impl& s = *impl_;
  require(y.size() == 2 * s.nx, "reference integrator: jacobian: y has {} entries, expected {}", y.size(), 2 * s.nx);
  require(s.jacobian(t, y.data()) == 0, "reference integrator: jacobian failed at t = {}: {}", t, s.last_rhs_problem);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(s.values.size());
  for (sunindextype r = 0; r < 2 * s.nx; ++r) {
    for (auto q = s.row_ptr[static_cast<std::size_t>(r)]; q < s.row_ptr[static_cast<std::size_t>(r + 1)]; ++q) {
      const auto sq = static_cast<std::size_t>(q);
      triplets.emplace_back(static_cast<int>(r), static_cast<int>(s.col_idx[sq]), s.values[sq]);
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> J(2 * s.nx, 2 * s.nx);
  J.setFromTriplets(triplets.begin(), triplets.end());
  return J;
}

const ReferenceStats& ReferenceIntegrator::stats() const { return impl_->stats; }

}  // namespace sflsh::fullspace
