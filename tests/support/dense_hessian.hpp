#pragma once
// A model::HessianSink that assembles a term's Hessian into one dense 3N × 3N matrix (small test meshes only).
#include <sflsh/model/problem.hpp>
#include <sflsh/model/terms.hpp>

#include <Eigen/Dense>

namespace sflsh::testing {

class DenseHessian final : public model::HessianSink {
 public:
  explicit DenseHessian(const model::Problem& problem)
      : problem_(problem), H(Eigen::MatrixXd::Zero(problem.num_dofs(), problem.num_dofs())) {}
  void add_tet(std::size_t, int e, const material::Matrix12d& block) override {
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        H.block<3, 3>(3 * problem_.tets(e, a), 3 * problem_.tets(e, b)) += block.block<3, 3>(3 * a, 3 * b);
  }
  void add_node(int node, const Eigen::Matrix3d& block) override { H.block<3, 3>(3 * node, 3 * node) += block; }

 private:
  const model::Problem& problem_;

 public:
  Eigen::MatrixXd H;
};

}  // namespace sflsh::testing
