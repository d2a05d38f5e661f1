// Constant nodal loads as a node potential (node_loads.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/scene/node_loads.hpp>

#include <algorithm>

namespace sflsh::scene {

NodeLoads::NodeLoads(std::vector<int> nodes)
    : nodes_(std::move(nodes)), force_(nodes_.size(), Eigen::Vector3d::Zero()) {
  require(
      std::is_sorted(nodes_.begin(), nodes_.end()) && std::adjacent_find(nodes_.begin(), nodes_.end()) == nodes_.end(),
      "node loads: the nodes must be ascending and distinct");
  require(nodes_.empty() || nodes_.front() >= 0, "node loads: negative node id {}", nodes_.empty() ? 0 : nodes_[0]);
}

void NodeLoads::clear() {
  for (int k : candidates_) force_[static_cast<std::size_t>(k)].setZero();
  candidates_.clear();
}

void NodeLoads::add(int entry, const Eigen::Vector3d& force) {
  require(entry >= 0 && static_cast<std::size_t>(entry) < nodes_.size(), "node loads: entry {} of {} nodes", entry,
          nodes_.size());
  require(force.allFinite(), "node loads: non-finite force on node {}", nodes_[static_cast<std::size_t>(entry)]);
  Eigen::Vector3d& f = force_[static_cast<std::size_t>(entry)];
  const auto at = std::lower_bound(candidates_.begin(), candidates_.end(), entry);
  if (at == candidates_.end() || *at != entry) candidates_.insert(at, entry);
  f += force;
}

Eigen::Vector3d NodeLoads::total() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k : candidates_) sum += force_[static_cast<std::size_t>(k)];
  return sum;
}

bool NodeLoads::begin_substep(double /*t0*/, double /*dt*/, const meshing::RowMatrixX3d& /*p_start*/,
                              const meshing::RowMatrixX3d& /*p_skinned_end*/) {
  return !candidates_.empty();
}

// u = −f·p (the work of a constant force): ∇u = −f, ∇²u = 0.
double NodeLoads::evaluate(int k, const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const {
  const Eigen::Vector3d& f = force_[static_cast<std::size_t>(candidates_[static_cast<std::size_t>(k)])];
  if (gradient) *gradient = -f;
  if (hessian) hessian->setZero();
  return -f.dot(p);
}

}  // namespace sflsh::scene
