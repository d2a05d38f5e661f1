#pragma once
// The consistent mass of the SUNDIALS reference (reference_integrator.hpp), without anything SUNDIALS-specific:
// the component-level matrix of its w rows, the coupling of free rows to prescribed components, and the
// prescribed posed accelerations that coupling multiplies. With y = [x; w] the reference integrates
//   M_y ẏ = f,  M_y = diag(I, M_w),
//   M_w[(i,α),(j,β)] = M_ij δ_αβ  on free components i,α and j,β;  identity rows (and columns) on prescribed ones,
//   f_w,(i,α) = [−A_i⁻ᵀ∇_i E + m_i g]_α − Σ_{(c,α) prescribed} M_ic a_c,α(t)   on free components, 0 on prescribed,
// with M the node-level consistent matrix (problem.mass_matrix()) and a_c the prescribed posed acceleration.
// "Free" and "prescribed" are components of x (the Dirichlet set); the reference allows a node with only some
// components prescribed where A_i = I, so component α of x and of p coincide there (the lumped rules).
#include <sflsh/fullspace/model_names.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

namespace sflsh::fullspace::detail {

/// The mass blocks of the w rows (3N × 3N, node-major components 3i + α, rows with sorted columns).
struct ComponentMass {
  Eigen::SparseMatrix<double, Eigen::RowMajor> free;  ///< M_w: M_ij δ_αβ on free pairs, 1 on prescribed diagonals
  Eigen::SparseMatrix<double, Eigen::RowMajor> coupling;  ///< M_FC: M_ic δ_αβ for free rows × prescribed columns
};

/// The blocks above from problem.mass_matrix() and the per-component mask of prescribed components (3N).
/// Throws sflsh::Error when the mass matrix is not finite or a free component has no positive diagonal mass.
ComponentMass component_mass(const Problem& problem, const std::vector<char>& constrained);

/// The posed velocity of the prescribed motion alone, ṗ = Ȧ x̄ + ḋ + A dx̄/dt with x̄(t) = X and the Dirichlet
/// values (what initial_state calls w), differenced in time [m/s²]:
///   a(t) ≈ (ṗ(t + δ) − ṗ(t − δ')) / (δ + δ'),  δ = 1e-4 s · max(1, |t|),  δ' = min(δ, t − t_start)
/// (central; one-sided at the start, where the forcing may not be defined before t_start). Meaningful on
/// prescribed components only (their posed value depends on t alone). Truncation ~δ² p⁗/6 (a 2 Hz, 1 cm
/// drive: ~6e-7 m/s² against 1.6 m/s²); round-off ~1e-16 |ṗ|/δ. The skinned trajectories are C¹ with
/// jumps in p̈ at frame times: the difference smooths each jump over 2δ.
Eigen::VectorXd prescribed_acceleration(const Problem& problem, double t, double t_start);

}  // namespace sflsh::fullspace::detail
