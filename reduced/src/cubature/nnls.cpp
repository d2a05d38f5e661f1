#include <sflsh/core/error.hpp>
#include <sflsh/reduced/nnls.hpp>

#include <Eigen/Cholesky>

#include <vector>

namespace sflsh::reduced {

namespace {

/// Least-squares solution restricted to the passive set P: G_PP z_P = h_P (z = 0 elsewhere).
Eigen::VectorXd passive_solve(const Eigen::MatrixXd& G, const Eigen::VectorXd& h, const std::vector<char>& passive) {
  std::vector<Eigen::Index> idx;
  for (Eigen::Index k = 0; k < h.size(); ++k)
    if (passive[static_cast<std::size_t>(k)]) idx.push_back(k);
  Eigen::MatrixXd Gp(idx.size(), idx.size());
  Eigen::VectorXd hp(idx.size());
  for (std::size_t a = 0; a < idx.size(); ++a) {
    hp[static_cast<Eigen::Index>(a)] = h[idx[a]];
    for (std::size_t b = 0; b < idx.size(); ++b)
      Gp(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = G(idx[a], idx[b]);
  }
  // A tiny diagonal shift keeps the factorization defined when passive columns are nearly dependent.
  const double shift = 1e-14 * (Gp.size() ? Gp.diagonal().cwiseAbs().maxCoeff() : 0.0);
  Gp.diagonal().array() += shift;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Gp);
  const Eigen::VectorXd zp = ldlt.solve(hp);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(h.size());
  for (std::size_t a = 0; a < idx.size(); ++a) z[idx[a]] = zp[static_cast<Eigen::Index>(a)];
  return z;
}

}  // namespace

NnlsResult nnls_normal_equations(const Eigen::MatrixXd& G, const Eigen::VectorXd& h, double tolerance,
                                 int max_iterations) {
  const Eigen::Index n = h.size();
  require(G.rows() == n && G.cols() == n, "nnls: Gram matrix is {}×{}, expected {}×{}", G.rows(), G.cols(), n, n);
  require(G.allFinite() && h.allFinite(), "nnls: non-finite input");
  if (max_iterations <= 0) max_iterations = static_cast<int>(3 * n + 10);
  NnlsResult result;
  result.x = Eigen::VectorXd::Zero(n);
  if (n == 0) {
    result.converged = true;
    return result;
  }
  const double scale = std::max(h.cwiseAbs().maxCoeff(), 1e-300);
  std::vector<char> passive(static_cast<std::size_t>(n), 0);
  Eigen::VectorXd& x = result.x;
  for (result.iterations = 0; result.iterations < max_iterations; ++result.iterations) {
    // Dual vector w = Aᵀ(b − Ax) = h − G x: the most positive entry among active variables enters.
    const Eigen::VectorXd w = h - G * x;
    Eigen::Index enter = -1;
    double best = tolerance * scale;
    for (Eigen::Index k = 0; k < n; ++k)
      if (!passive[static_cast<std::size_t>(k)] && w[k] > best) {
        best = w[k];
        enter = k;
      }
    if (enter < 0) {
      result.converged = true;
      return result;
    }
    passive[static_cast<std::size_t>(enter)] = 1;
    // Inner loop: move towards the passive-set solution, dropping variables that would turn negative.
    for (int inner = 0; inner <= n; ++inner) {
      const Eigen::VectorXd z = passive_solve(G, h, passive);
      bool feasible = true;
      for (Eigen::Index k = 0; k < n; ++k)
        if (passive[static_cast<std::size_t>(k)] && z[k] <= 0.0) feasible = false;
      if (feasible) {
        x = z;
        break;
      }
      double alpha = 1.0;
      for (Eigen::Index k = 0; k < n; ++k)
        if (passive[static_cast<std::size_t>(k)] && z[k] <= 0.0) alpha = std::min(alpha, x[k] / (x[k] - z[k]));
      x += alpha * (z - x);
      bool dropped = false;
      for (Eigen::Index k = 0; k < n; ++k)
        if (passive[static_cast<std::size_t>(k)] && x[k] <= 1e-15 * std::max(1.0, x.cwiseAbs().maxCoeff())) {
          passive[static_cast<std::size_t>(k)] = 0;
          x[k] = 0.0;
          dropped = true;
        }
      if (!dropped) break;  // numerical safety: alpha hit 1 without a zero; accept
    }
  }
  return result;
}

}  // namespace sflsh::reduced
