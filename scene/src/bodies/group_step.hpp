#pragma once
// Internal to the scene runner: one step of a group of bodies that may touch (body_groups.hpp). Every body is
// first solved against the others predicted; then each touching cluster exchanges its end-of-step surfaces
// until they agree (body_exchange.hpp), each body solved again from its start-of-step state. The result does
// not depend on the order of the bodies.
#include "bodies/scene_internal.hpp"
#include "contact/body_exchange.hpp"
#include "contact/scene_contact.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace sflsh::scene::detail {

class GroupStep {
 public:
  GroupStep(const Scene& scene, std::vector<std::unique_ptr<SceneBody>>& bodies, std::vector<BodyContact>& contact)
      : scene_(scene), bodies_(bodies), contact_(contact) {}

  /// Steps the group's bodies from t0 by h (`predicted`: every body's predicted surface at t0 + h, world); adds
  /// the solves' seconds per body and one record per touching cluster. threads: the group's bodies may be solved
  /// in parallel (no full-space body).
  void run(const std::vector<std::size_t>& group, const std::vector<RowMatrixX3d>& predicted, double t0, double h,
           std::vector<EffectSeconds>& seconds, std::vector<ExchangeRecord>& records, bool threads);

 private:
  void sweep(const std::vector<std::size_t>& group, const std::vector<RowMatrixX3d>& predicted, double t0, double h,
             std::vector<EffectSeconds>& seconds);
  void see_bodies(std::size_t b, const std::function<const RowMatrixX3d&(std::size_t)>& surface,
                  const std::vector<std::size_t>* only);
  void solve_bodies(const std::vector<std::size_t>& bodies, double t0, double h, std::vector<EffectSeconds>& seconds,
                    bool threads);
  void save_step_start(std::size_t b);
  void restore_step_start(std::size_t b);
  std::vector<std::size_t> touched_bodies(std::size_t b) const;
  ExchangeRecord exchange_cluster(const std::vector<std::size_t>& cluster, const std::vector<RowMatrixX3d>& predicted,
                                  double t0, double h, std::vector<EffectSeconds>& seconds, bool threads);
  double cluster_force(const std::vector<std::size_t>& cluster) const;
  double cluster_penetration(const std::vector<std::size_t>& cluster, const std::vector<RowMatrixX3d>& world);

  const Scene& scene_;
  std::vector<std::unique_ptr<SceneBody>>& bodies_;
  std::vector<BodyContact>& contact_;
};

}  // namespace sflsh::scene::detail
