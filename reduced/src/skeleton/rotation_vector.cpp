#include <sflsh/reduced/rotation_vector.hpp>

#include <cmath>

namespace sflsh::reduced {

namespace {

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d K;
  K << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return K;
}

/// a(s) = sin x / x and b(s) = (1 − cos x)/x² with x = √s, and their first two derivatives in s.
struct Coefficients {
  double a, da, d2a, b, db, d2b;
};

Coefficients coefficients(double s) {
  Coefficients c{};
  if (s < 1e-2) {  // Taylor series; the next terms are below 1e-12 relative at s = 1e-2
    const double s2 = s * s, s3 = s2 * s;
    c.a = 1.0 - s / 6.0 + s2 / 120.0 - s3 / 5040.0 + s2 * s2 / 362880.0;
    c.da = -1.0 / 6.0 + s / 60.0 - s2 / 1680.0 + s3 / 90720.0;
    c.d2a = 1.0 / 60.0 - s / 840.0 + s2 / 30240.0 - s3 / 1995840.0;
    c.b = 0.5 - s / 24.0 + s2 / 720.0 - s3 / 40320.0 + s2 * s2 / 3628800.0;
    c.db = -1.0 / 24.0 + s / 360.0 - s2 / 13440.0 + s3 / 907200.0;
    c.d2b = 1.0 / 360.0 - s / 6720.0 + s2 / 302400.0 - s3 / 23950080.0;
    return c;
  }
  const double x = std::sqrt(s), sn = std::sin(x), cs = std::cos(x);
  const double x2 = s, x3 = x2 * x, x4 = x2 * x2, x5 = x4 * x, x6 = x4 * x2;
  c.a = sn / x;
  c.da = (x * cs - sn) / (2.0 * x3);
  c.d2a = (-x2 * sn - 3.0 * x * cs + 3.0 * sn) / (4.0 * x5);
  c.b = (1.0 - cs) / x2;
  c.db = (x * sn - 2.0 + 2.0 * cs) / (2.0 * x4);
  c.d2b = (x2 * cs - 5.0 * x * sn + 8.0 - 8.0 * cs) / (4.0 * x6);
  return c;
}

}  // namespace

Eigen::Matrix3d rotation_of_vector(const Eigen::Vector3d& theta) {
  const Coefficients c = coefficients(theta.squaredNorm());
  const Eigen::Matrix3d K = cross_matrix(theta);
  return Eigen::Matrix3d::Identity() + c.a * K + c.b * K * K;  // R = I + aK + bK²
}

RotationVectorDerivatives rotation_vector_derivatives(const Eigen::Vector3d& theta) {
  const Coefficients c = coefficients(theta.squaredNorm());
  const Eigen::Matrix3d K = cross_matrix(theta), K2 = K * K;
  std::array<Eigen::Matrix3d, 3> E;  // ∂K/∂θ_k
  for (int k = 0; k < 3; ++k) E[static_cast<std::size_t>(k)] = cross_matrix(Eigen::Vector3d::Unit(k));
  RotationVectorDerivatives d;
  d.R = Eigen::Matrix3d::Identity() + c.a * K + c.b * K2;
  // ∂s/∂θ_k = 2θ_k.
  for (int k = 0; k < 3; ++k) {
    const auto sk = static_cast<std::size_t>(k);
    const Eigen::Matrix3d EK = E[sk] * K + K * E[sk];
    d.dR[sk] = 2.0 * theta[k] * (c.da * K + c.db * K2) + c.a * E[sk] + c.b * EK;
  }
  for (int k = 0; k < 3; ++k) {
    for (int l = k; l < 3; ++l) {
      const auto sk = static_cast<std::size_t>(k), sl = static_cast<std::size_t>(l);
      const double delta = k == l ? 1.0 : 0.0;
      const Eigen::Matrix3d EKk = E[sk] * K + K * E[sk], EKl = E[sl] * K + K * E[sl];
      const Eigen::Matrix3d m = (2.0 * delta * c.da + 4.0 * theta[k] * theta[l] * c.d2a) * K +
                                2.0 * c.da * (theta[k] * E[sl] + theta[l] * E[sk]) +
                                (2.0 * delta * c.db + 4.0 * theta[k] * theta[l] * c.d2b) * K2 +
                                2.0 * c.db * (theta[k] * EKl + theta[l] * EKk) + c.b * (E[sk] * E[sl] + E[sl] * E[sk]);
      d.d2R[sk][sl] = m;
      d.d2R[sl][sk] = m;
    }
  }
  return d;
}

}  // namespace sflsh::reduced
