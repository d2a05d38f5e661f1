#pragma once
// Central differences and error measures for the derivative tests (docs/style.md §4: a small helper in
// tests/, no dependency). Central differences have truncation error h²/6·|f'''| and rounding error
// ~ε_mach·|f|/h; with h = 1e-6 on quantities of order one both are ≲ 1e-9 relative.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <random>

namespace sflsh::testing {

/// ∂f/∂x by central differences; f maps an N-vector to a scalar.
template <int N, typename Fn>
Eigen::Matrix<double, N, 1> central_gradient(Fn&& f, const Eigen::Matrix<double, N, 1>& x, double h) {
  Eigen::Matrix<double, N, 1> g;
  for (int k = 0; k < N; ++k) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    g(k) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return g;
}

/// ∂f/∂x (M×N) by central differences; f maps an N-vector to an M-vector.
template <int M, int N, typename Fn>
Eigen::Matrix<double, M, N> central_jacobian(Fn&& f, const Eigen::Matrix<double, N, 1>& x, double h) {
  Eigen::Matrix<double, M, N> J;
  for (int k = 0; k < N; ++k) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    J.col(k) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

/// max |a − b| / max(max |b|, floor): the error relative to the size of the exact quantity (Vega's
/// finiteDifferenceTester reports the same kind of number).
template <typename A, typename B>
double relative_error(const A& approx, const B& exact, double floor = 0.0) {
  const double scale = std::max(exact.cwiseAbs().maxCoeff(), floor);
  return (approx - exact).cwiseAbs().maxCoeff() / scale;
}

/// max |A − Aᵀ| / max |A|.
template <typename A>
double asymmetry(const A& m) {
  return (m - m.transpose()).cwiseAbs().maxCoeff() / m.cwiseAbs().maxCoeff();
}

/// A uniformly random rotation (normalized Gaussian quaternion).
inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

}  // namespace sflsh::testing
