#pragma once
// Cubature of the elastic energy in the handle subspace (docs/physics.md §2.2; An, Kim, James 2008 for the
// form, Tapia et al. 2021 for doing without training simulations):
// \f[ E(q) \approx \sum_{c \in C} \omega_c V_c \Psi(F_c(q)),\quad
//     f = -\sum_c \omega_c V_c B_c^T \mathrm{vec}(P_c),\quad H = \sum_c \omega_c V_c B_c^T \tfrac{\partial P}{\partial
//     F}\Big|_c B_c \f]
// Data-oblivious: the points are chosen by farthest-point sampling over the rest volume (denser on the
// torso, like the handles), and the non-negative weights ω by NNLS so that the cubature reproduces
// integrals that need no training data — the total volume and the exact reduced forces at random handle
// displacements of a few millimetres to centimetres (generated, never simulated). Exact integration
// (every tet, ω = 1) stays available.
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <string>
#include <vector>

namespace sflsh::reduced {

/// Cubature points (tets) and weights ω_c (multiplying V_c Ψ_c).
struct Cubature {
  std::vector<int> tets;
  std::vector<double> weights;
  std::string method = "exact";  ///< "exact" | "voronoi" | "nnls"
  /// The coverage of the subspace's rest stiffness (cubature_coverage()); 0 when not measured.
  double stiffness_ratio_max = 0.0;
  double stiffness_ratio_min = 0.0;
  int size() const { return static_cast<int>(tets.size()); }
};

/// Every tet with ω = 1.
Cubature exact_cubature(int num_tets);

enum class CubatureWeighting { voronoi, nnls };

struct CubatureOptions {
  int count = 200;  ///< K cubature tets
  CubatureWeighting weighting = CubatureWeighting::nnls;
  std::vector<double> amplitudes{0.003, 0.01, 0.02};  ///< σ of the random handle displacements [m]
  int samples_per_amplitude = 8;
  unsigned seed = 20231212;
  /// Per-tet sampling density factor (empty = 1): distances are multiplied by it, as for the handles.
  std::vector<double> density;
  /// α: after the weights, every basis function keeps at least α of its exact Dirichlet energy in the
  /// cubature (cubature_coverage.hpp); 0 = off.
  double coverage = 0.5;
};

/// Farthest-point sample of `count` tets by centroid, started at the tet nearest the volume-weighted
/// centroid; deterministic. Distances are scaled by the per-tet density (empty: 1).
std::vector<int> farthest_point_tets(const model::Problem& problem, int count, const std::vector<double>& density);

/// Voronoi weights: every tet is given to its nearest cubature tet (by centroid); ω_c = (Σ V_e)/V_c.
std::vector<double> voronoi_weights(const model::Problem& problem, const std::vector<int>& tets);

/// Data-oblivious cubature for `problem` in `subspace`. Falls back to Voronoi weights (logged) when the
/// NNLS fit leaves the volume off by more than 5%; then raises functions the weights leave uncovered
/// (options.coverage, which may append tets).
Cubature select_cubature(const model::Problem& problem, const Subspace& subspace, const CubatureOptions& options);

/// The reduced rest stiffness K = ∂²E/∂q² at q = 0 of a cubature (3S × 3S).
Eigen::MatrixXd rest_stiffness(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature);

/// How the cubature's rest stiffness K_c covers the exact one K_x over the subspace: the extreme generalized
/// eigenvalues of K_x v = λ K_c v, i.e. max and min over directions v of vᵀK_x v / vᵀK_c v. A large λ_max is a
/// direction that strains tets the cubature does not see (they can leave the material's range at no cost to the
/// reduced energy); λ_max = +∞ when K_c is singular.
struct CubatureCoverage {
  double max_ratio = 0.0;
  double min_ratio = 0.0;
};
CubatureCoverage cubature_coverage(const Eigen::MatrixXd& exact_stiffness, const Eigen::MatrixXd& cubature_stiffness);

/// The smallest cubature of the farthest-point sequence, from options.count up by factors of `growth`, whose
/// coverage λ_max is ≤ max_ratio (the exact cubature when none below every tet is). Records the coverage.
Cubature select_covering_cubature(const model::Problem& problem, const Subspace& subspace,
                                  const CubatureOptions& options, double max_ratio, double growth = 1.25);

}  // namespace sflsh::reduced
