#pragma once
// Given forces on some mesh nodes, held constant over a step, as a node potential (model/node_potential.hpp):
//   u_k(p) = −f_k · p,   ∇u = −f_k,   ∇²u = 0.
// The scene applies with it the friction a free rigid object exerted on a body's skin in the object's own
// solve of the step (the opposite of the friction the object felt), so both sides of the contact feel it.
#include <sflsh/model/node_potential.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::scene {

class NodeLoads final : public model::NodePotential {
 public:
  /// nodes: ascending mesh node ids (unconstrained). Throws sflsh::Error on bad input.
  explicit NodeLoads(std::vector<int> nodes);

  /// Removes every load.
  void clear();
  /// Adds force f [N] (the posed frame of the problem) on entry k of nodes(). Throws on a non-finite force
  /// or an entry out of range.
  void add(int entry, const Eigen::Vector3d& force);
  /// The sum of the loads [N].
  Eigen::Vector3d total() const;

  // model::NodePotential
  const std::vector<int>& nodes() const override { return nodes_; }
  bool begin_substep(double t0, double dt, const meshing::RowMatrixX3d& p_start,
                     const meshing::RowMatrixX3d& p_skinned_end) override;
  const std::vector<int>& candidates() const override { return candidates_; }
  double evaluate(int k, const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  bool accept_substep(const meshing::RowMatrixX3d& /*p_end*/) override { return true; }
  int max_refinements() const override { return 0; }

 private:
  std::vector<int> nodes_;
  std::vector<Eigen::Vector3d> force_;  ///< per entry of nodes_ [N]
  std::vector<int> candidates_;         ///< entries with a load
};

}  // namespace sflsh::scene
