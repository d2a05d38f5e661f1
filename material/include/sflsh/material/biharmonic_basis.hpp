#pragma once
// Biharmonic basis functions φ_i of the material control points on a triangle surface (SFLSH §3:
// κ(s) = Σ_i φ_i(s) κ_i; §4: φ_i is also the window of the local regularizer Q_i), computed as bounded
// biharmonic weights (Jacobson, Baran, Popović, Sorkine 2011, "Bounded biharmonic weights for real-time
// deformation", Eq. 2–3; docs/physics.md §2.3). For each control point i:
// \f[ \phi_i = \arg\min_{\phi} \tfrac12\,\phi^T L M^{-1} L\,\phi
//     \quad\text{s.t.}\quad \phi(s_j) = \delta_{ij},\; 0 \le \phi \le 1, \f]
// with L the PSD cotangent Laplacian and M the lumped mass (surface_operators.hpp); natural boundary
// conditions on open surfaces (libigl `harmonic(L, M, k = 2)`). The rows are then divided by their sums
// to give a partition of unity, as BBW practice does (libigl's bbw + normalize_row_sums; the bound-free
// problem has Σ_i φ_i = 1 exactly, the bounded one nearly so). The result satisfies, to round-off:
//   φ_i(s_j) = δ_ij,  0 ≤ φ_i ≤ 1,  Σ_i φ_i = 1 at every vertex;  N = 1 gives φ ≡ 1.
// The bound constraints are solved exactly (a primal-dual active-set method with a provably terminating
// primal active-set fallback, each step a sparse LDLᵀ solve; KKT conditions checked), not by clamping.
#include <sflsh/material/surface_operators.hpp>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace sflsh::material {

struct BiharmonicOptions {
  bool bounded = true;    ///< impose 0 ≤ φ ≤ 1 (BBW); false: plain biharmonic interpolation (may leave [0, 1])
  bool normalize = true;  ///< divide each row by its sum (partition of unity); only changes bounded results
  MassLumping lumping = MassLumping::kVoronoi;
  int max_iterations = 50;  ///< primal-dual active-set iterations per function before the primal fallback
  bool parallel = true;     ///< solve the functions concurrently (TBB)
};

struct BiharmonicBasis {
  std::vector<int> control_vertices;  ///< N control vertices s_i, in the order of the columns
  Eigen::MatrixXd phi;                ///< #V by N: column i is φ_i at every vertex [dimensionless]
  std::vector<int> iterations;        ///< per function: sparse factorizations spent on the bounds (0 if none)
  std::vector<char> used_fallback;    ///< per function: the primal active-set fallback was needed
  bool bounded = true;                ///< options used, kept for caches
  bool normalized = true;
  MassLumping lumping = MassLumping::kVoronoi;
  std::uint64_t surface_fingerprint = 0;  ///< surface_fingerprint(V, F) of the surface it was computed on

  int num_vertices() const { return static_cast<int>(phi.rows()); }
  int num_functions() const { return static_cast<int>(phi.cols()); }
  int total_iterations() const;
};

/// Computes the basis. Throws sflsh::Error for an invalid surface (validate_surface), no control vertex,
/// one out of range or repeated, a connected component without a control vertex, a failed factorization,
/// an active-set method that does not converge, or a vertex where every bounded weight is zero.
/// @param[in] V                 #V by 3 vertex positions [m]
/// @param[in] F                 #F by 3 triangle vertex indices
/// @param[in] control_vertices  N distinct vertex indices (e.g. place_control_points)
BiharmonicBasis biharmonic_basis(const RowMatrixX3d& V, const RowMatrixX3i& F, const std::vector<int>& control_vertices,
                                 const BiharmonicOptions& options = {});

/// The energy matrix Q = L M⁻¹ L of the problem above (#V by #V, symmetric PSD, Q·1 = 0):
/// φᵀQφ is the discrete ∫(Δφ)² [1/m²] for a field with unit values.
SparseMatrixd biharmonic_energy_matrix(const RowMatrixX3d& V, const RowMatrixX3i& F,
                                       MassLumping lumping = MassLumping::kVoronoi);

/// A 64-bit FNV-1a hash of the vertex positions and faces, to tie a cached basis to its surface.
std::uint64_t surface_fingerprint(const RowMatrixX3d& V, const RowMatrixX3i& F);

/// Saves the basis as .npz (keys: phi (#V, N) f8, control_vertices (N,) i8, iterations (N,) i8,
/// used_fallback (N,) i8, options (3,) i8 = [bounded, normalized, lumping (0 Voronoi, 1 barycentric)],
/// surface_fingerprint () str of 16 hex digits), atomically.
void save_basis(const std::filesystem::path& path, const BiharmonicBasis& basis);

/// Loads a basis saved by save_basis; a missing key or inconsistent shape is a one-line sflsh::Error
/// naming the file and the key. Compare `surface_fingerprint` and `control_vertices` before reusing it.
BiharmonicBasis load_basis(const std::filesystem::path& path);

}  // namespace sflsh::material
