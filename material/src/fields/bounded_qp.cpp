// Box-constrained QP of bounded biharmonic weights: primal-dual active set with a primal active-set
// fallback. See bounded_qp.hpp for the method and its references.
#include "bounded_qp.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>

namespace sflsh::material::detail {

namespace {

enum State : signed char { kFree = 0, kLower = 1, kUpper = 2, kKnown = 3 };

struct Problem {
  const SparseMatrixd& Q;
  double multiplier_scale;  // max diag(Q): multipliers are compared relative to it
};

// Minimizes over the free variables with the held ones at their bounds and the known ones fixed:
// Q_FF x_F = −Q_F,held x_held. Overwrites the free entries of x.
void solve_free_block(const Problem& problem, const std::vector<signed char>& state, Eigen::VectorXd& x) {
  const auto n = static_cast<int>(x.size());
  std::vector<int> free, local(static_cast<std::size_t>(n), -1);
  Eigen::VectorXd fixed_part = x;
  for (int j = 0; j < n; ++j) {
    if (state[static_cast<std::size_t>(j)] != kFree) continue;
    local[static_cast<std::size_t>(j)] = static_cast<int>(free.size());
    free.push_back(j);
    fixed_part(j) = 0.0;
  }
  if (free.empty()) return;
  const Eigen::VectorXd coupling = problem.Q * fixed_part;
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(free.size()));
  for (std::size_t i = 0; i < free.size(); ++i) rhs(static_cast<Eigen::Index>(i)) = -coupling(free[i]);
  Eigen::SimplicialLDLT<SparseMatrixd> ldlt(principal_submatrix(problem.Q, free, local));
  require(ldlt.info() == Eigen::Success,
          "bounded biharmonic weights: the free block ({} vertices) is singular (a surface component without "
          "a control point?)",
          free.size());
  const Eigen::VectorXd solution = ldlt.solve(rhs);
  require(solution.allFinite(), "bounded biharmonic weights: non-finite values in the free-block solve");
  for (std::size_t i = 0; i < free.size(); ++i) x(free[i]) = solution(static_cast<Eigen::Index>(i));
}

// The worst wrong-sign multiplier among held variables, relative to the multiplier scale, and its index.
// At a lower bound the multiplier is g_j = (Qx)_j and must be ≥ 0; at an upper bound it must be ≤ 0.
std::pair<double, int> worst_multiplier(const Problem& problem, const std::vector<signed char>& state,
                                        const Eigen::VectorXd& x) {
  const Eigen::VectorXd g = problem.Q * x;
  double worst = 0.0;
  int index = -1;
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    const signed char s = state[static_cast<std::size_t>(j)];
    const double wrong = s == kLower ? -g(j) : (s == kUpper ? g(j) : 0.0);
    if (wrong / problem.multiplier_scale > worst) worst = wrong / problem.multiplier_scale, index = static_cast<int>(j);
  }
  return {worst, index};
}

void hold_at_bound(std::vector<signed char>& state, Eigen::VectorXd& x, Eigen::Index j, bool upper) {
  state[static_cast<std::size_t>(j)] = upper ? kUpper : kLower;
  x(j) = upper ? 1.0 : 0.0;
}

// Primal active set (Nocedal & Wright 2006, Alg. 16.3) from a feasible x: returns factorizations spent.
int primal_active_set(const Problem& problem, std::vector<signed char>& state, Eigen::VectorXd& x,
                      const BoxQpSettings& settings, int budget) {
  for (Eigen::Index j = 0; j < x.size(); ++j) {  // feasible start: clamp, and hold what sits on a bound
    auto& s = state[static_cast<std::size_t>(j)];
    if (s == kKnown) continue;
    s = kFree;
    if (x(j) <= 0.0) hold_at_bound(state, x, j, false);
    if (x(j) >= 1.0) hold_at_bound(state, x, j, true);
  }
  int spent = 0;
  bool at_subproblem_minimum = false;
  while (true) {
    if (at_subproblem_minimum) {
      const auto [worst, index] = worst_multiplier(problem, state, x);
      if (worst <= settings.multiplier_tolerance) return spent;
      state[static_cast<std::size_t>(index)] = kFree;  // drop the most violated constraint only: descent
    }
    require(spent < budget, "bounded biharmonic weights: the primal active-set fallback did not converge in {} solves",
            budget);
    Eigen::VectorXd target = x;
    solve_free_block(problem, state, target);
    ++spent;
    // Step from x towards the subproblem minimum, stopping at the first bound met (the ratio test).
    double alpha = 1.0;
    Eigen::Index blocking = -1;
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      if (state[static_cast<std::size_t>(j)] != kFree) continue;
      const double p = target(j) - x(j);
      const double ratio = p < 0.0 ? x(j) / -p : (p > 0.0 ? (1.0 - x(j)) / p : 2.0);
      if (ratio < alpha) alpha = ratio, blocking = j;
    }
    for (Eigen::Index j = 0; j < x.size(); ++j)
      if (state[static_cast<std::size_t>(j)] == kFree) x(j) += alpha * (target(j) - x(j));
    at_subproblem_minimum = blocking < 0;
    if (blocking >= 0) hold_at_bound(state, x, blocking, target(blocking) > x(blocking));
    for (Eigen::Index j = 0; j < x.size(); ++j) {  // round-off beyond a bound: hold it there
      if (state[static_cast<std::size_t>(j)] != kFree) continue;
      if (x(j) < 0.0) hold_at_bound(state, x, j, false);
      if (x(j) > 1.0) hold_at_bound(state, x, j, true);
    }
  }
}

}  // namespace

SparseMatrixd principal_submatrix(const SparseMatrixd& Q, const std::vector<int>& free, const std::vector<int>& local) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(Q.nonZeros()));
  for (const int col : free) {
    for (SparseMatrixd::InnerIterator it(Q, col); it; ++it) {
      const int r = local[static_cast<std::size_t>(it.row())];
      if (r >= 0) triplets.emplace_back(r, local[static_cast<std::size_t>(col)], it.value());
    }
  }
  const auto m = static_cast<Eigen::Index>(free.size());
  SparseMatrixd sub(m, m);
  sub.setFromTriplets(triplets.begin(), triplets.end());
  return sub;
}

BoxQpResult solve_box_qp(const SparseMatrixd& Q, const std::vector<int>& known, const Eigen::VectorXd& start,
                         const BoxQpSettings& settings) {
  const Problem problem{Q, std::max(Q.diagonal().cwiseAbs().maxCoeff(), 1e-300)};
  BoxQpResult result;
  Eigen::VectorXd x = start;
  std::vector<signed char> state(static_cast<std::size_t>(x.size()), kFree);
  for (const int k : known) state[static_cast<std::size_t>(k)] = kKnown;

  // Primal-dual active set. First update from the unconstrained minimizer (all multipliers zero).
  const double tol = settings.primal_tolerance;
  std::vector<std::vector<signed char>> history;
  bool converged = false;
  while (!converged) {
    std::vector<signed char> next = state;
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      auto& s = next[static_cast<std::size_t>(j)];
      if (s == kFree && (x(j) < -tol || x(j) > 1.0 + tol)) s = x(j) < 0.0 ? kLower : kUpper;
    }
    if (result.iterations > 0) {  // held variables with a wrong-sign multiplier are released
      const Eigen::VectorXd g = Q * x;
      for (Eigen::Index j = 0; j < x.size(); ++j) {
        auto& s = next[static_cast<std::size_t>(j)];
        if ((s == kLower && state[static_cast<std::size_t>(j)] == kLower &&
             -g(j) > settings.multiplier_tolerance * problem.multiplier_scale) ||
            (s == kUpper && state[static_cast<std::size_t>(j)] == kUpper &&
             g(j) > settings.multiplier_tolerance * problem.multiplier_scale))
          s = kFree;
      }
    }
    if (next == state && result.iterations > 0) {
      converged = true;  // sets unchanged: free ones feasible, held ones with right-sign multipliers (KKT)
      break;
    }
    if (next == state) break;  // the unconstrained minimizer is already feasible
    const bool cycled = std::find(history.begin(), history.end(), next) != history.end();
    if (cycled || result.iterations >= settings.max_iterations) {
      result.used_fallback = true;
      break;
    }
    history.push_back(state);
    state = std::move(next);
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      const signed char s = state[static_cast<std::size_t>(j)];
      if (s == kLower || s == kUpper) x(j) = s == kUpper ? 1.0 : 0.0;
    }
    solve_free_block(problem, state, x);
    ++result.iterations;
  }
  if (result.used_fallback)
    result.iterations += primal_active_set(problem, state, x, settings, 20 * settings.max_iterations);

  for (Eigen::Index j = 0; j < x.size(); ++j) {
    if (state[static_cast<std::size_t>(j)] == kKnown) continue;
    result.max_bound_violation = std::max({result.max_bound_violation, -x(j), x(j) - 1.0});
    x(j) = std::clamp(x(j), 0.0, 1.0);
  }
  result.max_multiplier_violation = worst_multiplier(problem, state, x).first;
  require(result.max_bound_violation <= 1e3 * tol,
          "bounded biharmonic weights: the solution violates the bounds by {:.3g} (active set not converged)",
          result.max_bound_violation);
  result.x = std::move(x);
  return result;
}

}  // namespace sflsh::material::detail
