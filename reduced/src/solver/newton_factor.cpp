#include <sflsh/reduced/newton_factor.hpp>

#include <vector>

namespace sflsh::reduced {

namespace {

/// The coordinates outside [begin, begin + size), ascending.
std::vector<Eigen::Index> others(Eigen::Index n, Eigen::Index begin, Eigen::Index size) {
  std::vector<Eigen::Index> o;
  o.reserve(static_cast<std::size_t>(n - size));
  for (Eigen::Index i = 0; i < n; ++i)
    if (i < begin || i >= begin + size) o.push_back(i);
  return o;
}

}  // namespace

bool NewtonFactor::compute(const Eigen::MatrixXd& hessian, Eigen::Index patch_begin, Eigen::Index patch_size) {
  const Eigen::Index n = hessian.rows();
  begin_ = patch_begin;
  size_ = patch_size > 0 && patch_begin >= 0 && patch_begin + patch_size <= n && patch_size < n ? patch_size : 0;
  if (size_ == 0) {
    dense_.compute(hessian);
    ok_ = dense_.info() == Eigen::Success;
    return ok_;
  }
  // C = H_PP as a sparse matrix (its exact zeros are the mesh's non-neighbours).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(size_) * 100);
  for (Eigen::Index j = 0; j < size_; ++j)
    for (Eigen::Index i = 0; i < size_; ++i)
      if (const double v = hessian(begin_ + i, begin_ + j); v != 0.0) entries.emplace_back(i, j, v);
  Eigen::SparseMatrix<double> c(size_, size_);
  c.setFromTriplets(entries.begin(), entries.end());
  auto patch = std::make_shared<Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>>(c);
  patch_ = patch;
  if (patch->info() != Eigen::Success) {
    ok_ = false;
    return false;
  }
  others_ = others(n, begin_, size_);
  const std::vector<Eigen::Index>& o = others_;
  const auto m = static_cast<Eigen::Index>(o.size());
  coupling_.resize(size_, m);
  Eigen::MatrixXd schur(m, m);
  for (Eigen::Index b = 0; b < m; ++b) {
    coupling_.col(b) = hessian.col(o[static_cast<std::size_t>(b)]).segment(begin_, size_);
    for (Eigen::Index a = 0; a < m; ++a)
      schur(a, b) = hessian(o[static_cast<std::size_t>(a)], o[static_cast<std::size_t>(b)]);
  }
  x_ = patch_->solve(coupling_);
  schur.noalias() -= coupling_.transpose() * x_;
  dense_.compute(schur);
  ok_ = dense_.info() == Eigen::Success && x_.allFinite();
  return ok_;
}

Eigen::VectorXd NewtonFactor::solve(const Eigen::VectorXd& r) const {
  if (size_ == 0) return dense_.solve(r);
  const Eigen::Index n = r.size();
  const std::vector<Eigen::Index>& o = others_;
  Eigen::VectorXd r_other(static_cast<Eigen::Index>(o.size()));
  for (std::size_t k = 0; k < o.size(); ++k) r_other[static_cast<Eigen::Index>(k)] = r[o[k]];
  const Eigen::VectorXd y = patch_->solve(Eigen::VectorXd(r.segment(begin_, size_)));
  const Eigen::VectorXd d_other = dense_.solve(r_other - coupling_.transpose() * y);
  Eigen::VectorXd d(n);
  d.segment(begin_, size_) = y - x_ * d_other;
  for (std::size_t k = 0; k < o.size(); ++k) d[o[k]] = d_other[static_cast<Eigen::Index>(k)];
  return d;
}

}  // namespace sflsh::reduced
