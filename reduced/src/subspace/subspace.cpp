#include <sflsh/core/error.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

void Subspace::add_displacement(const Eigen::VectorXd& q, Eigen::Ref<Eigen::VectorXd> x) const {
  require(q.size() == num_dofs() && x.size() == 3 * num_nodes(),
          "subspace: q has {} entries (expected {}), x {} (expected {})", q.size(), num_dofs(), x.size(),
          3 * num_nodes());
  for (int i = 0; i < num_nodes(); ++i) {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (SparseRowMatrix::InnerIterator it(basis, i); it; ++it) u += it.value() * q.segment<3>(3 * it.col());
    x.segment<3>(3 * i) += u;
  }
}

std::vector<int> Subspace::active_nodes() const {
  std::vector<int> out;
  for (int i = 0; i < num_nodes(); ++i) {
    for (SparseRowMatrix::InnerIterator it(basis, i); it; ++it) {
      if (it.value() != 0.0) {
        out.push_back(i);
        break;
      }
    }
  }
  return out;
}

Eigen::VectorXd Subspace::project_gradient(const Eigen::VectorXd& v) const {
  require(v.size() == 3 * num_nodes(), "subspace: gradient has {} entries, expected {}", v.size(), 3 * num_nodes());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(num_dofs());
  for (int i = 0; i < num_nodes(); ++i)
    for (SparseRowMatrix::InnerIterator it(basis, i); it; ++it)
      g.segment<3>(3 * it.col()) += it.value() * v.segment<3>(3 * i);
  return g;
}

}  // namespace sflsh::reduced
