#pragma once
// Every basis function of the subspace gets elastic resistance from the cubature. A force-matching fit
// (NNLS over random handle displacements) can leave a function whose support holds no cubature tet with
// weight — a handle the cubature does not see, which then swings on inertia alone (issue 18: a 61 mm kink at
// one elbow of a symmetric motion). The pass below measures each function's Dirichlet energy
//   D_s = Σ_e V_e |∇b_s|²_e  (exact)   and   C_s = Σ_c ω_c V_c |∇b_s|²_c  (cubature)
// and, for every function with C_s < α D_s, adds weight on the tet carrying most of D_s until C_s = α D_s.
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

/// Per basis function: the cubature's share C_s / D_s of its Dirichlet energy (1 for exact cubature; 1 for
/// a function with no energy, e.g. none in the mesh).
Eigen::VectorXd cubature_coverage(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature);

/// Raises `cubature` (appending tets when needed) until every function's share is at least `fraction`
/// (0 < fraction ≤ 1). Returns how many functions needed it.
int cover_every_function(const model::Problem& problem, const Subspace& subspace, Cubature& cubature, double fraction);

}  // namespace sflsh::reduced
