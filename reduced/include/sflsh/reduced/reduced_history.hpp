#pragma once
// The posed history of the reduced model (model/time_integrator.hpp) over its inertia nodes
// (reduced_inertia.hpp): gathered from a full state, written back into one, and Newmark's starting
// acceleration computed in the subspace.
//
// Newmark's p̈ at the start. The reduced Euler–Lagrange equations of L = ½ṗᵀMṗ − E(q) + gᵀMp with
// p = z(t) + J(t) q (J = ∂p/∂q = A B, zero rows off the basis) are Jᵀ M p̈ = −∇E(q) + Jᵀ M g (the J̇ terms of
// d/dt ∂L/∂q̇ and ∂L/∂q cancel). With p̈ = J q̈ + ζ, ζ the posed acceleration of the prescribed motion at fixed
// coordinates, (JᵀMJ) q̈ = −∇E(q) + JᵀM(g − ζ) and a = J q̈ + ζ. JᵀMJ is the mass Hessian at ĥ = 1, positive
// definite when every basis function moves mass. ζ = z̈ + J̈ q is exact for a state without elastic velocity
// (q̇ = 0, as model::initial_state gives); otherwise it omits the 2 J̇ q̇ of the elastic velocity, which the
// state does not carry in coordinates.
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::reduced {

/// The entries of a full 3N vector at `nodes` (3 per node).
Eigen::VectorXd gather_nodes(const Eigen::VectorXd& full, const std::vector<int>& nodes);
/// Writes 3 entries per node of `values` into the full 3N vector `full` at `nodes`.
void scatter_nodes(const Eigen::VectorXd& values, const std::vector<int>& nodes, Eigen::VectorXd& full);

/// ζ of every node at coordinates q (3N) [m/s²]: a forward difference (δ = 1 µs, the step model::initial_acceleration
/// uses) of the posed velocity ṗ(t) = Ȧ(t) x(t) + ḋ(t) + A(t) ẋ_D(t), x(t) = x_D(t) + (B ⊗ I₃) q.
Eigen::VectorXd prescribed_acceleration(const model::Problem& problem, const Subspace& subspace,
                                        const Eigen::VectorXd& q, double t);

/// a = J q̈ + ζ on the inertia nodes (3 per node) at the inertia's current time, from the elastic gradient ∇E(q)
/// (3S) [N] and ζ on the inertia nodes (see the file comment). Throws sflsh::Error when JᵀMJ is singular or the
/// result is not finite.
Eigen::VectorXd subspace_acceleration(const ReducedInertia& inertia, const Eigen::VectorXd& elastic_gradient,
                                      const Eigen::VectorXd& zeta);

}  // namespace sflsh::reduced
