#pragma once
// Central differences for the scene tests (docs/style.md §4). With h = 1e-6 m on distances of order 0.1 m
// the truncation error h²/6·|φ'''| (|φ'''| ~ 1/ρ² with ρ ≳ 0.05 m) and the rounding error ε/h are
// both ≲ 1e-8, far below the 1e-6 tolerances used.
#include "../material/finite_difference.hpp"  // relative_error

#include <Eigen/Core>

#include <algorithm>
#include <functional>

namespace sflsh::testing {

inline Eigen::Vector3d central_gradient(const std::function<double(const Eigen::Vector3d&)>& f,
                                        const Eigen::Vector3d& x, double h = 1e-6) {
  Eigen::Vector3d g;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    g(k) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return g;
}

inline Eigen::Matrix3d central_jacobian(const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f,
                                        const Eigen::Vector3d& x, double h = 1e-6) {
  Eigen::Matrix3d J;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    J.col(k) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

}  // namespace sflsh::testing
