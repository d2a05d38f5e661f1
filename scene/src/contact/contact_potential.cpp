// Penalty contact (contact_potential.hpp, docs/contact.md).
//
// Derivatives of one node–obstacle term, with g = ∇φ, H_φ = ∇²φ and s = δ − φ > 0 where it is active:
//   u   = ½ k s²
//   ∇u  = −k s g
//   ∇²u = k g gᵀ − k s H_φ
// The first part (Gauss–Newton) is PSD. The curvature part −k s H_φ is negative semi-definite for a
// convex obstacle (H_φ ⪰ 0: sphere, capsule, box edges and corners, convex mesh features) and positive
// semi-definite for a concave one (a mesh's concave edge or vertex region). Because φ is a distance,
// H_φ g = 0, so g is an eigenvector of ∇²u (eigenvalue k) and the curvature part only acts in the
// tangent plane. Clamping the negative eigenvalues of the summed 3×3 Hessian to zero (the nearest PSD
// matrix in the Frobenius norm) therefore keeps the exact Hessian wherever it is already PSD (concave
// features, flat faces), and reduces to Gauss–Newton k g gᵀ at convex ones: the tangential softening of
// a convex obstacle is what would make Newton's model non-convex.
#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/scene/contact_potential.hpp>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>

namespace sflsh::scene {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

void ContactParameters::validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  require(positive(stiffness), "contact: stiffness must be positive [N/m³] (got {})", stiffness);
  require(positive(default_node_area), "contact: default_node_area must be positive [m²] (got {})", default_node_area);
  require(std::isfinite(margin) && margin >= 0.0, "contact: margin must be ≥ 0 [m] (got {})", margin);
  require(positive(tolerance), "contact: tolerance must be positive [m] (got {})", tolerance);
  require(std::isfinite(refinement_factor) && refinement_factor > 1.0,
          "contact: refinement_factor must be > 1 (got {})", refinement_factor);
  require(max_refinements >= 0, "contact: max_refinements must be ≥ 0 (got {})", max_refinements);
  require(std::isfinite(broad_phase_safety) && broad_phase_safety >= 0.0,
          "contact: broad_phase_safety must be ≥ 0 [m] (got {})", broad_phase_safety);
}

std::vector<double> lumped_vertex_areas(const RowMatrixX3d& vertices, const RowMatrixX3i& triangles) {
  require(triangles.size() == 0 || (triangles.minCoeff() >= 0 && triangles.maxCoeff() < vertices.rows()),
          "lumped_vertex_areas: triangle indices must lie in [0, {})", vertices.rows());
  std::vector<double> area(static_cast<std::size_t>(vertices.rows()), 0.0);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(triangles(f, 0)).transpose(), b = vertices.row(triangles(f, 1)).transpose(),
                          c = vertices.row(triangles(f, 2)).transpose();
    const double third = (b - a).cross(c - a).norm() / 6.0;
    for (int k = 0; k < 3; ++k) area[static_cast<std::size_t>(triangles(f, k))] += third;
  }
  return area;
}

ContactPotential::ContactPotential(std::vector<int> nodes, std::vector<double> areas,
                                   std::vector<ContactObstacle> obstacles, const ContactParameters& parameters)
    : nodes_(std::move(nodes)), area_(std::move(areas)), obstacles_(std::move(obstacles)), parameters_(parameters) {
  parameters_.validate();
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    require(nodes_[k] >= 0 && (k == 0 || nodes_[k] > nodes_[k - 1]),
            "contact: node ids must be ascending and ≥ 0 (entry {})", k);
  if (area_.empty()) area_.assign(nodes_.size(), parameters_.default_node_area);
  require(area_.size() == nodes_.size(), "contact: {} areas for {} nodes", area_.size(), nodes_.size());
  for (std::size_t k = 0; k < area_.size(); ++k)
    require(std::isfinite(area_[k]) && area_[k] >= 0.0, "contact: area of entry {} must be ≥ 0 [m²] (got {})", k,
            area_[k]);
  require(obstacles_.size() <= 64, "contact: at most 64 obstacles (got {})", obstacles_.size());
  for (std::size_t j = 0; j < obstacles_.size(); ++j)
    require(obstacles_[j].shape != nullptr, "contact: obstacle {} has no shape", j);
  const auto n = static_cast<Eigen::Index>(nodes_.size());
  factor_.assign(nodes_.size(), 1.0);
  mask_.assign(nodes_.size(), 0);
  force_ = meshing::RowMatrixX3d::Zero(n, 3);
  penetration_ = Eigen::VectorXd::Zero(n);
  obstacle_force_.assign(obstacles_.size(), Eigen::Vector3d::Zero());
  obstacle_torque_.assign(obstacles_.size(), Eigen::Vector3d::Zero());
}

double ContactPotential::node_stiffness(int k) const {
  const auto i = static_cast<std::size_t>(k);
  return parameters_.stiffness * area_[i] * factor_[i];
}

bool ContactPotential::begin_substep(double t0, double dt, const meshing::RowMatrixX3d& p_start,
                                     const meshing::RowMatrixX3d& p_skinned_end) {
  const auto start = Clock::now();
  const auto n = static_cast<Eigen::Index>(nodes_.size());
  require(p_start.rows() == n && p_skinned_end.rows() == n, "contact: begin_substep expects {} rows (got {} and {})", n,
          p_start.rows(), p_skinned_end.rows());
  require(std::isfinite(t0) && std::isfinite(dt) && dt > 0.0, "contact: bad substep t0 = {}, dt = {}", t0, dt);
  const bool retry = !last_accepted_ && t0 == substep_t0_ && dt == substep_dt_;
  if (!retry) {
    if (!last_accepted_ && t0 > substep_t0_) {
      // The previous substep ended without accept_substep (it was idle): the objects moved to t0 without
      // a reaction. (t0 == substep_t0_ is the same interval started again, e.g. with a smaller dt.)
      for (auto& o : obstacles_)
        if (o.motion) o.motion->commit(t0, Eigen::Vector3d::Zero());
      force_.setZero();
      penetration_.setZero();
      for (auto& f : obstacle_force_) f.setZero();
      for (auto& tq : obstacle_torque_) tq.setZero();
    }
    substep_refinements_ = 0;
  }
  substep_t0_ = t0;
  substep_dt_ = dt;
  t_end_ = t0 + dt;
  last_accepted_ = false;
  for (auto& o : obstacles_)
    if (o.motion) o.shape->set_pose(o.motion->pose(t_end_));

  // Broad phase. φ is 1-Lipschitz, so a node whose end position p_end satisfies |p_end − p_start| ≤ r
  // can only reach φ < δ if φ(p_start) < δ + r. r is estimated by the skinned motion |Δ| of this step
  // plus `broad_phase_safety` for the elastic motion (the end pose of the obstacle is used throughout).
  ++stats_.broad_phase_passes;
  std::fill(mask_.begin(), mask_.end(), 0);
  const Eigen::VectorXd motion = (p_skinned_end - p_start).rowwise().norm();
  const double extra = parameters_.margin + parameters_.broad_phase_safety;
  Aabb cloud;
  for (Eigen::Index k = 0; k < n; ++k) {
    cloud.extend(p_start.row(k).transpose());
    cloud.extend(p_skinned_end.row(k).transpose());
  }
  const double reach_max = extra + (n > 0 ? motion.maxCoeff() : 0.0);
  for (std::size_t j = 0; j < obstacles_.size(); ++j) {
    const Obstacle& shape = *obstacles_[j].shape;
    const Aabb box = shape.bounds();
    if (n == 0 || box.distance(cloud) > reach_max) continue;  // far away: costs one box test
    const std::uint64_t bit = std::uint64_t{1} << j;
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Vector3d ps = p_start.row(k).transpose(), pe = p_skinned_end.row(k).transpose();
      const double reach = extra + motion(k);
      if (std::min(box.distance(ps), box.distance(pe)) > reach) continue;
      stats_.broad_phase_queries += 2;
      if (std::min(shape.distance(ps), shape.distance(pe)) < reach) mask_[static_cast<std::size_t>(k)] |= bit;
    }
  }
  candidates_.clear();
  for (std::size_t k = 0; k < mask_.size(); ++k) {
    if (mask_[k] != 0)
      candidates_.push_back(static_cast<int>(k));
    else
      factor_[k] = 1.0;  // a node that left the contact zone starts again from the base stiffness
  }
  stats_.candidates += static_cast<std::int64_t>(candidates_.size());
  stats_.seconds += seconds_since(start);
  return !candidates_.empty();
}

double ContactPotential::evaluate_masked(int k, std::uint64_t mask, const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                                         Eigen::Matrix3d* hessian) const {
  if (gradient) gradient->setZero();
  if (hessian) hessian->setZero();
  if (!p.allFinite()) return std::numeric_limits<double>::quiet_NaN();  // let the solver see it
  const double delta = parameters_.margin;
  const double stiffness = node_stiffness(k);
  double u = 0.0;
  std::int64_t evaluations = 0;
  for (std::size_t j = 0; mask != 0 && j < obstacles_.size(); ++j) {
    if (!(mask & (std::uint64_t{1} << j))) continue;
    ++evaluations;
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    const double phi = obstacles_[j].shape->distance(p, (gradient || hessian) ? &g : nullptr, hessian ? &H : nullptr);
    const double s = delta - phi;
    if (!(s > 0.0)) continue;
    u += 0.5 * stiffness * s * s;
    if (gradient) *gradient -= stiffness * s * g;
    if (hessian) *hessian += stiffness * (g * g.transpose() - s * H);
  }
  narrow_evaluations_.fetch_add(evaluations, std::memory_order_relaxed);
  if (hessian && parameters_.project_hessian) {
    // Nearest PSD matrix: clamp the eigenvalues at zero (see the header comment of this file).
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(*hessian);
    const Eigen::Vector3d lambda = eigen.eigenvalues().cwiseMax(0.0);
    *hessian = eigen.eigenvectors() * lambda.asDiagonal() * eigen.eigenvectors().transpose();
  }
  return u;
}

double ContactPotential::evaluate(int c, const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                                  Eigen::Matrix3d* hessian) const {
  // c indexes candidates() (as p_end of accept_substep does), the convention both integrators use.
  assert(c >= 0 && c < static_cast<int>(candidates_.size()));
  const auto start = Clock::now();
  const int k = candidates_[static_cast<std::size_t>(c)];
  const double u = evaluate_masked(k, mask_[static_cast<std::size_t>(k)], p, gradient, hessian);
  evaluate_nanoseconds_.fetch_add(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start).count(),
                                  std::memory_order_relaxed);
  return u;
}

bool ContactPotential::accept_substep(const meshing::RowMatrixX3d& p_end) {
  const auto start = Clock::now();
  require(p_end.rows() == static_cast<Eigen::Index>(candidates_.size()),
          "contact: accept_substep expects {} rows (one per candidate), got {}", candidates_.size(), p_end.rows());
  unresolved_.clear();
  // Penetration of each candidate at the end of the substep.
  std::vector<int> too_deep;
  Eigen::VectorXd depth = Eigen::VectorXd::Zero(p_end.rows());
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    const auto k = static_cast<std::size_t>(candidates_[c]);
    const Eigen::Vector3d p = p_end.row(static_cast<Eigen::Index>(c)).transpose();
    for (std::size_t j = 0; j < obstacles_.size(); ++j)
      if (mask_[k] & (std::uint64_t{1} << j))
        depth(static_cast<Eigen::Index>(c)) =
            std::max(depth(static_cast<Eigen::Index>(c)), -obstacles_[j].shape->distance(p));
    if (!(depth(static_cast<Eigen::Index>(c)) <= parameters_.tolerance)) too_deep.push_back(static_cast<int>(c));
  }
  if (!too_deep.empty() && substep_refinements_ < parameters_.max_refinements) {
    for (int c : too_deep)
      factor_[static_cast<std::size_t>(candidates_[static_cast<std::size_t>(c)])] *= parameters_.refinement_factor;
    ++substep_refinements_;
    ++stats_.refinements;
    stats_.seconds += seconds_since(start);
    return false;  // last_accepted_ stays false: the next begin_substep of this interval is a retry
  }
  if (!too_deep.empty()) {
    // Refinements used up (or a non-finite position): refused for good, with the deepest node and its obstacle.
    ++stats_.unresolved;
    int deepest = too_deep.front();
    for (int c : too_deep)
      if (!(depth(c) <= depth(deepest))) deepest = c;
    const auto k = static_cast<std::size_t>(candidates_[static_cast<std::size_t>(deepest)]);
    const Eigen::Vector3d p = p_end.row(deepest).transpose();
    std::size_t worst = 0;
    double worst_depth = -std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < obstacles_.size(); ++j)
      if ((mask_[k] & (std::uint64_t{1} << j)) && -obstacles_[j].shape->distance(p) > worst_depth) {
        worst = j;
        worst_depth = -obstacles_[j].shape->distance(p);
      }
    const std::string name = obstacles_.empty() || obstacles_[worst].name.empty() ? fmt::format("obstacle {}", worst)
                                                                                  : obstacles_[worst].name;
    unresolved_ = std::isfinite(depth(deepest))
                      ? fmt::format(
                            "contact with {} unresolved at t = {:.6g} s: skin node {} is {:.2f} mm inside it "
                            "after {} stiffening(s) (tolerance {:.2f} mm)",
                            name, t_end_, nodes_[k], 1000.0 * depth(deepest), substep_refinements_,
                            1000.0 * parameters_.tolerance)
                      : fmt::format("contact with {} at t = {:.6g} s: skin node {} has a non-finite position", name,
                                    t_end_, nodes_[k]);
    substep_refinements_ = 0;
    stats_.seconds += seconds_since(start);
    return false;
  }

  // Accepted: forces on the nodes and their reactions on the obstacles.
  force_.setZero();
  penetration_.setZero();
  for (auto& f : obstacle_force_) f.setZero();
  for (auto& tq : obstacle_torque_) tq.setZero();
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    const int k = candidates_[c];
    const Eigen::Vector3d p = p_end.row(static_cast<Eigen::Index>(c)).transpose();
    penetration_(k) = depth(static_cast<Eigen::Index>(c));
    for (std::size_t j = 0; j < obstacles_.size(); ++j) {
      const std::uint64_t bit = std::uint64_t{1} << j;
      if (!(mask_[static_cast<std::size_t>(k)] & bit)) continue;
      Eigen::Vector3d gradient;
      evaluate_masked(k, bit, p, &gradient, nullptr);
      force_.row(k) -= gradient.transpose();  // on the node: −∇u
      obstacle_force_[j] += gradient;         // on the obstacle: the reaction +∇u
      obstacle_torque_[j] += (p - obstacles_[j].shape->pose().translation).cross(gradient);
    }
  }
  for (std::size_t j = 0; j < obstacles_.size(); ++j)
    if (obstacles_[j].motion) obstacles_[j].motion->commit(t_end_, obstacle_force_[j]);
  stats_.max_penetration = std::max(stats_.max_penetration, depth.size() > 0 ? depth.maxCoeff() : 0.0);
  const double total = force_.colwise().sum().norm();
  if (total > stats_.max_force) {
    stats_.max_force = total;
    stats_.max_force_time = t_end_;
  }
  ++stats_.accepted;
  substep_refinements_ = 0;
  last_accepted_ = true;
  stats_.seconds += seconds_since(start);
  return true;
}

ContactStats ContactPotential::stats() const {
  ContactStats s = stats_;
  s.narrow_phase_evaluations = narrow_evaluations_.load(std::memory_order_relaxed);
  s.seconds += 1e-9 * static_cast<double>(evaluate_nanoseconds_.load(std::memory_order_relaxed));
  return s;
}

void ContactPotential::reset_stats() {
  stats_ = {};
  narrow_evaluations_ = 0;
  evaluate_nanoseconds_ = 0;
}

}  // namespace sflsh::scene
