#pragma once
// Cubature of the elastic energy in the handle subspace (docs/physics.md §2.2; An, Kim, James 2008 for the
// form, Tapia et al. 2021 for doing without training simulations):
// \f[ E(q) \approx \sum_{c \in C} \omega_c V_c \Psi(F_c(q)),\quad
//     f = -\sum_c \omega_c V_c B_c^T \mathrm{vec}(P_c),\quad H = \sum_c \omega_c V_c B_c^T \tfrac{\partial P}{\partial F}\Big|_c B_c \f]
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
  std::string method = "exact";   ///< "exact" | "voronoi" | "nnls"
  int size() const { return static_cast<int>(tets.size()); }
};

/// Every tet with ω = 1.
Cubature exact_cubature(int num_tets);

enum class CubatureWeighting { voronoi, nnls };

struct CubatureOptions {
  int count = 200;                              ///< K cubature tets
  CubatureWeighting weighting = CubatureWeighting::nnls;
  std::vector<double> amplitudes{0.003, 0.01, 0.02};   ///< σ of the random handle displacements [m]
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

}  // namespace sflsh::reduced
