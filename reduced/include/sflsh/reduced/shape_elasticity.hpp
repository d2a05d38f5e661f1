#pragma once
// Shape-dependent elasticity (SFLSH §4): per control point i, the normalized parameters
//   κ̂_i(β) = A_iᵀ β + b_i,   A_i ∈ R^{10×3}, b_i ∈ R³                                  (eq. 1)
// with κ̂ = κ / κ_max (parameters.hpp), and the regularizers of the regression coefficients A_i:
//   L² (Q_i = I) and the paper's local-covariance metric
//   M_i = Σ_t φ_i(t) a(t) B(t)ᵀ B(t),   Q_i = (M_i / m)⁻¹,   m = mean_i tr(M_i)/10          (eqs. 3–4)
// over the template's region vertices t (a: vertex area, B(t): the 3×10 shape blend-shape block),
// assembled into r_reg = √λ L p with L from the Cholesky factors Q_i = L_i L_iᵀ, scaled by 1/√N and
// zero for the b_i                                                                           (eq. 7)
// so that ‖r_reg‖² = (λ/N) Σ_i tr(A_iᵀ Q_i A_i). SFLSH leaves the scale open; the common factor m scales the
// covariance, not its inverse, so that the directions of β that change the local shape most (eigenvalues of
// M_i / m of order one) are penalized about as much as under L² and the ones that barely change it far more
// (docs/fit.md, "The local metric's scale").
//
// Parameter vector p (33N): per control point, vec(A_i) column-major (A_i's column for h, then Y_t, Y_n;
// each 10 entries), then b_i (h, Y_t, Y_n).
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/material/parameters.hpp>
#include <sflsh/meshing/layer_mesh.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

namespace sflsh::reduced {

inline constexpr int kParamsPerControl = body::kNumBetas * material::kNumKappa + material::kNumKappa;  // 33

using ShapeMatrix = Eigen::Matrix<double, body::kNumBetas, material::kNumKappa>;  ///< A_i (10×3)
using ShapeMetric = Eigen::Matrix<double, body::kNumBetas, body::kNumBetas>;      ///< Q_i (10×10)

struct ShapeElasticity {
  std::vector<ShapeMatrix> A;  ///< per control point
  material::KappaMatrix b;     ///< N×3 normalized intercepts

  int num_controls() const { return static_cast<int>(b.rows()); }
  /// A ≡ 0 and b_i = the normalized κ of every control point (a shape-independent material).
  static ShapeElasticity constant(const material::KappaMatrix& kappa_normalized);
  /// κ̂_i(β) for every control point (N×3), not clamped (eq. 1).
  material::KappaMatrix kappa_normalized(const body::Betas& beta) const;

  Eigen::VectorXd pack() const;
  static ShapeElasticity unpack(const Eigen::VectorXd& p, int num_controls);
};

/// The rows of dq/dp for one subject (eq. 8): κ̂ = J p with J (3N × 33N), row 3i + c = control i, column c.
Eigen::SparseMatrix<double> kappa_jacobian(const body::Betas& beta, int num_controls);

enum class Regularizer {
  l2,     ///< Q_i = I
  local,  ///< Q_i of eq. 4 (the paper's)
  none,   ///< no regularizer (λ = 0; the minimum-norm solution where the data do not determine A_i)
};
/// "L2", "ours" or "none": the names of validate's tables and fit fingerprints.
const char* regularizer_name(Regularizer r);
/// "l2", "local" or "none": the spelling of files and command lines.
const char* regularizer_key(Regularizer r);
/// Parses "l2", "local" or "none"; throws "<what>: … (expected l2, local or none)" otherwise.
Regularizer parse_regularizer(const std::string& text, const std::string& what);

/// M_i / m of eq. 3 (the local covariance of the shape blend shapes, normalized so that mean_i tr = 10) for the
/// basis φ (R × N) over the region vertices `region_vertices` (body indices) of the template with per-vertex
/// areas `area` (R). Throws when a moment matrix is not positive definite.
std::vector<ShapeMetric> local_shape_covariance(const body::BodyModel& model, const std::vector<int>& region_vertices,
                                                const Eigen::VectorXd& area, const Eigen::MatrixXd& phi);
/// Q_i of eq. 4: the inverses of local_shape_covariance.
std::vector<ShapeMetric> local_shape_metric(const body::BodyModel& model, const std::vector<int>& region_vertices,
                                            const Eigen::VectorXd& area, const Eigen::MatrixXd& phi);
/// Q_i of eq. 4 on a layer: its region vertices with their Voronoi areas on the template surface.
std::vector<ShapeMetric> layer_shape_metric(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                            const Eigen::MatrixXd& phi);

/// L of eq. 7 (without √λ): (30N × 33N) sparse; block i maps vec(A_i) to (1/√N) (I₃ ⊗ L_iᵀ) vec(A_i).
/// `metric` empty → L² (Q_i = I).
Eigen::SparseMatrix<double> regularizer_matrix(const std::vector<ShapeMetric>& metric, int num_controls);

/// Lower and upper bounds of p: b_i within the normalized parameter ranges, A_i entries within ±a_max
/// (a per-unit-β change of a_max of the normalized range is already extreme: β spans about ±3).
void parameter_bounds(const material::ParameterBounds& bounds, int num_controls, double a_max, Eigen::VectorXd& lower,
                      Eigen::VectorXd& upper);

/// κ̂ clamped into the normalized ranges; `clamped` (optional) receives the number of entries moved.
material::KappaMatrix clamp_normalized(const material::KappaMatrix& kappa, const material::ParameterBounds& bounds,
                                       int* clamped = nullptr);

}  // namespace sflsh::reduced
