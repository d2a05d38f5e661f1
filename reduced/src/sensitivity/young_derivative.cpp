// ∂P/∂Y of the orthotropic StVK–Fung material (young_derivative.hpp). P_Y = a T + b N with T = I − nnᵀ,
// N = nnᵀ, a = Y_t^{1/4}, b = Y_n^{1/4}; both T and N are symmetric projectors, so D = ∂P_Y/∂Y is symmetric.
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/young_derivative.hpp>

#include <cmath>

namespace sflsh::reduced {

Eigen::Vector2d young_moduli(const material::OrthotropicFung& m) {
  const double b = m.normal.dot(m.scaling * m.normal);  // nᵀ P_Y n = Y_n^{1/4}
  const double a = 0.5 * (m.scaling.trace() - b);       // tr P_Y = 2a + b
  return {std::pow(a, 4.0), std::pow(b, 4.0)};
}

YoungStressDerivative d2psi_ortho_fung_dF_dyoung(const Eigen::Matrix3d& F, const material::OrthotropicFung& m) {
  if (!F.allFinite()) throw_error("young derivative: non-finite deformation gradient");
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d N = m.normal * m.normal.transpose();
  const Eigen::Matrix3d T = I - N;
  const double b = m.normal.dot(m.scaling * m.normal);
  const double a = 0.5 * (m.scaling.trace() - b);
  const Eigen::Matrix3d& PY = m.scaling;
  const Eigen::Matrix3d E = material::green_strain(F);
  const Eigen::Matrix3d E_hat = PY * E * PY;                                      // Ê = P_Y E P_Y
  const Eigen::Matrix3d M = 2.0 * m.mu0 * E_hat + m.lambda0 * E_hat.trace() * I;  // ∂Ψ₀/∂Ê
  const double psi0 = m.mu0 * E_hat.squaredNorm() + 0.5 * m.lambda0 * E_hat.trace() * E_hat.trace();
  const Eigen::Matrix3d S0 = PY * M * PY;
  const Eigen::Matrix3d P0 = F * S0;

  // φ'(x), φ''(x) as in eval_ortho_fung.
  const double x = 2.0 * psi0 * m.inv_c;
  double dphi = 1.0, d2phi = 0.0;
  if (m.inv_c != 0.0) {
    if (x <= material::kFungExponentCap) {
      dphi = d2phi = std::exp(x);
    } else if (m.overflow == material::ExponentOverflow::kThrow || !std::isfinite(x)) {
      throw_error("young derivative: Fung exponent 2Ψ₀/c = {:.4g} exceeds the cap {}", x, material::kFungExponentCap);
    } else {
      dphi = std::exp(material::kFungExponentCap);
      d2phi = 0.0;
    }
  }

  const auto derivative = [&](const Eigen::Matrix3d& D, double dc_over_c) {
    const Eigen::Matrix3d dE_hat = D * E * PY + PY * E * D;   // ∂Ê
    const double dpsi0 = (M.array() * dE_hat.array()).sum();  // M : ∂Ê
    const Eigen::Matrix3d dS0 =
        D * M * PY + PY * M * D + PY * (2.0 * m.mu0 * dE_hat + m.lambda0 * dE_hat.trace() * I) * PY;
    const double dx = 2.0 * dpsi0 * m.inv_c - x * dc_over_c;  // x = 2Ψ₀/c
    return Eigen::Matrix3d(d2phi * dx * P0 + dphi * (F * dS0));
  };
  YoungStressDerivative out;
  const double young_tangent = std::pow(a, 4.0), young_normal = std::pow(b, 4.0);
  // ∂a/∂Y_t = ¼ Y_t^{−3/4} = a / (4 Y_t); c ∝ Y_t under both finite Fung scales.
  out.tangent = derivative((0.25 * a / young_tangent) * T, 1.0 / young_tangent);
  out.normal = derivative((0.25 * b / young_normal) * N, 0.0);
  return out;
}

}  // namespace sflsh::reduced
