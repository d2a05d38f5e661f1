#pragma once
// The heterogeneous soft-tissue parameters κ = (h, Y_t, Y_n) (SFLSH §3): per control point κ_i, and the
// field κ(s) = Σ_i φ_i(s) κ_i over the surface. For the fit they are "normalized by their maximum
// values" (SFLSH §4): κ̂ = κ / κ_max, component-wise, with κ_max the upper bounds below.
//
// Bounds (SFLSH gives no ranges; docs/physics.md §6.5 proposes Y in ~0.5–50 kPa and h in [0.2, 0.9]):
//   thickness      h   ∈ [0.1, 0.9]       fraction of the maximum surface-to-skeleton thickness (docs/architecture.md
//   §3);
//                                         0.1 rather than 0.2 leaves room for thin layers while keeping
//                                         elements away from zero height; 0.9 keeps the inner surface off
//                                         the bones.
//   young_tangent  Y_t ∈ [500, 50000] Pa  two decades around soft-tissue values (docs/physics.md §6.5),
//   young_normal   Y_n ∈ [500, 50000] Pa  which also contains docs/architecture.md §8's 100× contrast.
// Normalized, these are h ∈ [0.111, 1], Y ∈ [0.01, 1]. A φ that is a convex combination (bounded
// biharmonic basis: φ ≥ 0, Σφ = 1) keeps the field κ(s) inside the bounds wherever the κ_i are.
#include <Eigen/Core>

#include <array>
#include <string_view>
#include <vector>

namespace sflsh::material {

/// κ of one point, physical units.
struct Kappa {
  double thickness = 0.0;      ///< h: fraction of the maximum surface-to-skeleton thickness [dimensionless]
  double young_tangent = 0.0;  ///< Y_t: Young modulus in the tangent plane [Pa]
  double young_normal = 0.0;   ///< Y_n: Young modulus along the normal [Pa]
};

/// Column order of κ in matrices, and the names used in files and messages.
enum KappaColumn : int { kThickness = 0, kYoungTangent = 1, kYoungNormal = 2 };
inline constexpr int kNumKappa = 3;
inline constexpr std::array<std::string_view, kNumKappa> kKappaNames = {"thickness", "young_tangent", "young_normal"};

/// Rows are points (control points or vertices), columns (h, Y_t, Y_n).
using KappaMatrix = Eigen::Matrix<double, Eigen::Dynamic, kNumKappa, Eigen::RowMajor>;

struct ParameterRange {
  double min = 0.0;
  double max = 0.0;
};

/// The physical range any Young modulus (bounds, control points, verify problems) must lie in [Pa]: generous
/// (from gels to cartilage-like stiffness, four decades either side of the default bounds) but finite enough
/// that the Fung energy, its Hessian and the solvers stay in double range. Files outside it are refused at load.
inline constexpr ParameterRange kYoungModulusLimits{1.0, 1e9};
/// The largest Fung saturation s accepted (s > 0): with c = Y_t/s the exponent is ≈ s·E², so s = 100 already
/// stiffens 10 % strain by e; 1e308 overflows the energy at any strain.
inline constexpr double kSaturationMax = 100.0;

/// Closed ranges of the physical parameters; the maxima are the normalization scales.
struct ParameterBounds {
  ParameterRange thickness{0.1, 0.9};
  ParameterRange young_tangent{500.0, 50000.0};  ///< [Pa]
  ParameterRange young_normal{500.0, 50000.0};   ///< [Pa]

  const ParameterRange& operator[](int column) const;
  Eigen::RowVector3d minimum() const;
  Eigen::RowVector3d maximum() const;
};

/// Throws sflsh::Error naming the field unless every range is finite with 0 < min ≤ max, the thickness
/// maximum is ≤ 1 (h is a fraction) and the Young modulus ranges lie within kYoungModulusLimits.
void validate(const ParameterBounds& bounds);

/// Throws sflsh::Error "<what>: <field> = <value> is outside [min, max] <unit>" (or not finite).
void validate(const Kappa& kappa, const ParameterBounds& bounds, std::string_view what);
/// The same for every row of a physical KappaMatrix; `what` is followed by the row index.
void validate(const KappaMatrix& kappa, const ParameterBounds& bounds, std::string_view what);

Eigen::RowVector3d to_row(const Kappa& kappa);
Kappa from_row(const Eigen::Ref<const Eigen::RowVector3d>& row);
KappaMatrix to_matrix(const std::vector<Kappa>& kappa);
std::vector<Kappa> from_matrix(const KappaMatrix& kappa);

/// κ̂ = κ / κ_max per column (SFLSH §4). Does not validate.
KappaMatrix normalize(const KappaMatrix& physical, const ParameterBounds& bounds);
/// κ = κ̂ · κ_max per column.
KappaMatrix denormalize(const KappaMatrix& normalized, const ParameterBounds& bounds);
/// The normalized bounds: [min/max, 1] per column.
ParameterBounds normalized_bounds(const ParameterBounds& bounds);

/// A neutral starting value (the N = 1 fit's initial guess): mid-range thickness and the geometric mean
/// of each Young modulus range (the fit is naturally logarithmic in stiffness).
Kappa initial_kappa(const ParameterBounds& bounds = {});

/// The field at every vertex: κ(s_v) = Σ_i φ_i(s_v) κ_i, i.e. phi · kappa.
/// @param[in] phi    #V by N basis (biharmonic_basis(...).phi)
/// @param[in] kappa  N by 3 control values (physical or normalized: the map is linear)
/// @return #V by 3
KappaMatrix evaluate_field(const Eigen::MatrixXd& phi, const KappaMatrix& kappa);

}  // namespace sflsh::material
