#pragma once
// Time integrators as incremental potentials (docs/integrators.md). A step of length h of every integrator,
// in the full-space solver and in the reduced model alike, minimizes over the elastic state
//   Φ(x) = 1/(2ĥ²) (p(x) − p̃)ᵀ M (p(x) − p̃) + E(x) − gᵀ M p(x) + U(p(x)),
// with p the posed node positions, M the lumped or consistent mass (mass.hpp) and U the node potentials; the
// integrator only sets ĥ and p̃ from the posed history, and updates the history from the minimizer:
//   backward Euler:       ĥ = h,    p̃ = p_n + h v_n;                       v = (p − p_n)/h, a = (v − v_n)/h
//   BDF2 (variable step, ω = h/h_{n−1}; α0 = (1+2ω)/(1+ω), α1 = −(1+ω), α2 = ω²/(1+ω)):
//                         ĥ = h/α0, p̃ = −(α1 p_n + α2 p_{n−1})/α0 − ĥ (α1 v_n + α2 v_{n−1})/α0;
//                         v = (α0 p + α1 p_n + α2 p_{n−1})/h
//   Newmark (β = ¼, γ = ½, trapezoidal): ĥ = h/2, p̃ = p_n + h v_n + h²/4 a_n;  a = (p − p̃)/ĥ², v = v_n + h/2 (a_n + a)
// The minimizer satisfies A_iᵀ[M (p − p̃)/ĥ²]_i = −∇_i E + A_iᵀ[M g]_i − ∇_i U: the discrete equation of motion
// with p̈ ≈ (p − p̃)/ĥ² (every integrator's acceleration at t_{n+1}). Backward Euler damps (first order), BDF2
// damps mildly (second order), Newmark conserves the energy of a linear system (second order, no damping).
// BDF2 takes its first step, and the first step after the step length grew more than twofold (variable-step
// BDF2 loses zero-stability beyond ω = 1 + √2), as backward Euler. Newmark needs a_n: initial_acceleration.
#include <sflsh/model/problem.hpp>

#include <Eigen/Core>

#include <string_view>

namespace sflsh::model {

enum class Integrator { backward_euler, bdf2, newmark };

/// "backward_euler" | "bdf2" | "newmark"; anything else throws sflsh::Error naming `where` and the values.
Integrator parse_integrator(std::string_view text, std::string_view where);
std::string_view to_string(Integrator integrator);

/// The integrator of every body run that names none (`simulate`, `sweep`, `compare`, scenes, Python): BDF2 with
/// consistent masses (mass.hpp kDefaultMassKind) keeps ≥ 95 % of a converged run's σ at 60 fps in both solvers,
/// where the paper's backward Euler with lumped masses keeps 64–77 %, and Newmark, undamped, lets the reduced
/// model's cubature modes grow until its guard fails (docs/decisions.md, "Defaults: BDF2 with consistent masses").
inline constexpr Integrator kDefaultIntegrator = Integrator::bdf2;
/// The paper's integrator (SFLSH §5: implicit Euler), one option away: --integrator backward_euler --mass lumped.
inline constexpr Integrator kPaperIntegrator = Integrator::backward_euler;

/// The posed kinematics an integrator carries between steps, for the nodes it tracks (3 entries per node).
struct PosedHistory {
  Eigen::VectorXd p;           ///< positions at t_n [m]
  Eigen::VectorXd v;           ///< velocities at t_n [m/s]
  Eigen::VectorXd a;           ///< accelerations at t_n [m/s²] (Newmark; empty until known)
  Eigen::VectorXd p_previous;  ///< positions at t_{n−1} [m] (BDF2; empty at the start)
  Eigen::VectorXd v_previous;  ///< velocities at t_{n−1} [m/s]
  double h_previous = 0.0;     ///< t_n − t_{n−1} [s]
};

/// What one step minimizes beside E, gravity and U: 1/(2ĥ²)(p − p̃)ᵀM(p − p̃).
struct InertiaTarget {
  Integrator integrator = Integrator::backward_euler;  ///< the one this step uses (BDF2 may start as backward Euler)
  double h = 0.0;                                      ///< step [s]
  double h_eff = 0.0;                                  ///< ĥ [s]
  Eigen::VectorXd p_tilde;                             ///< p̃ [m]
};

/// ĥ and p̃ of `integrator` for a step of h from `history`. Newmark throws when history.a is missing.
InertiaTarget inertia_target(Integrator integrator, const PosedHistory& history, double h);

/// The history at t_{n+1} from the step's minimizer p (the same nodes as the history).
void advance_history(const InertiaTarget& target, PosedHistory& history, const Eigen::VectorXd& p_new);

/// The history of a full-space state whose posed positions are p (3N): v = w, a, previous step.
PosedHistory history_of(const State& state, Eigen::VectorXd p);
/// Stores the history's velocities, accelerations and previous step back into the state.
void store_history(const PosedHistory& history, State& state);

/// p̈ of a full-space state from the equations of motion (what Newmark needs at its first step) [m/s²]:
/// [M p̈]_i = −A_i⁻ᵀ ∇_i E(x) + m_i g on the free components (M lumped or consistent, as the problem says),
/// the prescribed motion's acceleration on constrained ones (a forward difference of its velocity). Node
/// potentials are not included (contact is inactive at the start of a run). Zero for a problem without mass.
Eigen::VectorXd initial_acceleration(const Problem& problem, const State& state);

}  // namespace sflsh::model
