// A group's step with the exchange between touching bodies (group_step.hpp).
#include "bodies/group_step.hpp"

#include "contact/body_exchange.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

namespace sflsh::scene::detail {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

// A group's step. First every body is solved against the others predicted (their current elastic displacement
// carried by the new pose; bodies of other groups are out of reach). Then the bodies that touch (touching
// clusters) exchange their end-of-step surfaces until they agree (exchange_cluster). Every body is solved from
// its start-of-step state against the same surfaces whatever its place in the scene, so the order of the
// bodies does not decide who gives way.
void GroupStep::run(const std::vector<std::size_t>& group, const std::vector<RowMatrixX3d>& predicted, double t0,
                    double h, std::vector<EffectSeconds>& seconds, std::vector<ExchangeRecord>& records, bool threads) {
  if (scene_.effects.body_contact && group.size() > 1 && !scene_.contact.body_exchange)
    return sweep(group, predicted, t0, h, seconds);
  const bool exchange = scene_.effects.body_contact && group.size() > 1;
  if (exchange)
    for (std::size_t b : group) save_step_start(b);
  for (std::size_t b : group)
    see_bodies(
        b, [&](std::size_t o) -> const RowMatrixX3d& { return predicted[o]; }, nullptr);
  solve_bodies(group, t0, h, seconds, threads);
  if (!exchange) return;
  std::vector<std::vector<std::size_t>> touches(group.size());
  for (std::size_t i = 0; i < group.size(); ++i) touches[i] = touched_bodies(group[i]);
  for (const auto& cluster : touching_clusters(group, touches))
    records.push_back(exchange_cluster(cluster, predicted, t0, h, seconds, threads));
}

// [contact] body_exchange = false: one Gauss–Seidel sweep in scene order, each body against the bodies before it
// at the step's end and the ones after it predicted (the body solved first takes most of the deformation).
void GroupStep::sweep(const std::vector<std::size_t>& group, const std::vector<RowMatrixX3d>& predicted, double t0,
                      double h, std::vector<EffectSeconds>& seconds) {
  std::vector<RowMatrixX3d> stepped(bodies_.size());
  for (std::size_t b : group) {
    see_bodies(
        b, [&](std::size_t o) -> const RowMatrixX3d& { return stepped[o].rows() > 0 ? stepped[o] : predicted[o]; },
        nullptr);
    bodies_[b]->step(t0, h, seconds[b]);
    stepped[b] = bodies_[b]->world_surface();
  }
}

// Sets body b's body obstacles to the surfaces `surface(o)` (world) of the other bodies o, of all of them or
// only of those in `only`.
void GroupStep::see_bodies(std::size_t b, const std::function<const RowMatrixX3d&(std::size_t)>& surface,
                           const std::vector<std::size_t>* only) {
  BodyContact& c = contact_[b];
  if (!c.bodies) return;
  const auto clock = Clock::now();
  const Rigid body_from_world = bodies_[b]->placement().inverse();
  for (std::size_t k = 0; k < c.other.size(); ++k) {
    const auto o = static_cast<std::size_t>(c.other[k]);
    if (only && std::find(only->begin(), only->end(), o) == only->end()) continue;
    c.surfaces[k]->set_vertices(body_from_world.apply(surface(o)));
  }
  c.surface_seconds += seconds_since(clock);
}

// Steps the bodies from t0 by h, each on its own (they see fixed surfaces of each other): in parallel when the
// group has no full-space body.
void GroupStep::solve_bodies(const std::vector<std::size_t>& bodies, double t0, double h,
                             std::vector<EffectSeconds>& seconds, bool threads) {
  if (!threads || bodies.size() < 2) {
    for (std::size_t b : bodies) bodies_[b]->step(t0, h, seconds[b]);
    return;
  }
  std::vector<std::string> errors(bodies.size());
  tbb::parallel_for(std::size_t{0}, bodies.size(), [&](std::size_t i) {
    try {
      bodies_[bodies[i]]->step(t0, h, seconds[bodies[i]]);
    } catch (const std::exception& e) {
      errors[i] = e.what();
    }
  });
  for (const std::string& e : errors)
    if (!e.empty()) throw_error("{}", e);
}

void GroupStep::save_step_start(std::size_t b) {
  bodies_[b]->save_step_start();
  BodyContact& c = contact_[b];
  if (c.objects) c.objects_start = c.objects->checkpoint();
  if (c.bodies) c.bodies_start = c.bodies->checkpoint();
}

void GroupStep::restore_step_start(std::size_t b) {
  bodies_[b]->restore_step_start();
  BodyContact& c = contact_[b];
  if (c.objects) c.objects->restore(c.objects_start);
  if (c.bodies) c.bodies->restore(c.bodies_start);
}

// The other bodies whose surfaces body b's contact candidates are near in the last solve.
std::vector<std::size_t> GroupStep::touched_bodies(std::size_t b) const {
  const BodyContact& c = contact_[b];
  if (!c.bodies) return {};
  std::uint64_t mask = 0;
  for (int k : c.bodies->candidates()) mask |= c.bodies->obstacle_mask(k);
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < c.other.size(); ++j)
    if (mask & (std::uint64_t{1} << j)) out.push_back(static_cast<std::size_t>(c.other[j]));
  return out;
}

namespace {

// Where a cluster's exchanged surfaces lie in one stacked vector (3 entries per vertex, world).
struct ClusterExchangeLayout {
  std::vector<std::size_t> felt;     ///< cluster positions of the exchanged surfaces
  std::vector<Eigen::Index> offset;  ///< where each felt surface starts; the last entry is the total size
};

// The surfaces some other body of the cluster feels (has a body-contact potential against): only they are
// exchanged (a skinned body's potential-free solve reads no surface).
ClusterExchangeLayout cluster_exchange_layout(const std::vector<std::size_t>& cluster,
                                              const std::vector<std::unique_ptr<SceneBody>>& bodies,
                                              const std::vector<BodyContact>& contact) {
  const std::size_t n = cluster.size();
  ClusterExchangeLayout layout;
  std::vector<std::size_t>& felt = layout.felt;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && contact[cluster[j]].bodies) {
        felt.push_back(i);
        break;
      }
  std::vector<Eigen::Index>& offset = layout.offset;
  offset.assign(felt.size() + 1, 0);
  for (std::size_t k = 0; k < felt.size(); ++k)
    offset[k + 1] = offset[k] + 3 * static_cast<Eigen::Index>(bodies[cluster[felt[k]]]->model().num_vertices());
  return layout;
}

// Copies the felt surfaces, `surface(i)` for cluster position i, into the stacked vector `stacked`.
template <typename Surface>
void cluster_exchange_stack(const ClusterExchangeLayout& layout, const Surface& surface, Eigen::VectorXd& stacked) {
  const std::vector<Eigen::Index>& offset = layout.offset;
  for (std::size_t k = 0; k < layout.felt.size(); ++k)
    stacked.segment(offset[k], offset[k + 1] - offset[k]) =
        Eigen::Map<const Eigen::VectorXd>(surface(layout.felt[k]).data(), offset[k + 1] - offset[k]);
}

// Copies the stacked vector `stacked` back into the felt surfaces of `surfaces` (per cluster position).
void cluster_exchange_unstack(const ClusterExchangeLayout& layout, const Eigen::VectorXd& stacked,
                              std::vector<RowMatrixX3d>& surfaces) {
  const std::vector<Eigen::Index>& offset = layout.offset;
  for (std::size_t k = 0; k < layout.felt.size(); ++k)
    surfaces[layout.felt[k]] =
        Eigen::Map<const RowMatrixX3d>(stacked.data() + offset[k], (offset[k + 1] - offset[k]) / 3, 3);
}

// The largest move of a surface vertex from x to y [m].
double cluster_exchange_largest_move(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  double largest = 0.0;
  for (Eigen::Index v = 0; v < x.size() / 3; ++v)
    largest = std::max(largest, (y.segment<3>(3 * v) - x.segment<3>(3 * v)).norm());
  return largest;
}

// Restart: the quasi-Newton model is dropped when kStall exchanges have not brought the residual norm below
// kProgress of the best so far (a contact set that changed makes the old differences mislead it). Tracks the
// residual norm `norm` in `best` and `since_best`; returns whether to restart now.
bool cluster_exchange_stalled(double norm, double& best, int& since_best) {
  constexpr int kStall = 4;
  constexpr double kProgress = 0.9;
  if (norm < kProgress * best) {
    best = norm;
    since_best = 0;
  } else if (++since_best >= kStall) {
    best = norm;
    since_best = 0;
    return true;
  }
  return false;
}

// Logs how a cluster's exchange ended at t1: a warning when it did not converge, the figures at debug level.
void cluster_exchange_log(const ExchangeRecord& r, const std::vector<std::size_t>& cluster,
                          const std::vector<std::unique_ptr<SceneBody>>& bodies, const ContactSpec& contact,
                          double t1) {
  if (!r.converged) {
    std::string names;
    for (std::size_t b : cluster) names += (names.empty() ? "" : ", ") + bodies[b]->name();
    logger()->warn(
        "body contact: bodies {} did not agree within [contact] max_exchanges = {} at t = {:.4f} s (surfaces "
        "{:.3f} mm apart, tolerance {:.3f} mm; contact force changed {:.1f} %); the last solve is kept",
        names, contact.max_exchanges, t1, 1e3 * r.surface_residual, 1e3 * contact.exchange_tolerance,
        100.0 * r.force_change);
  }
  logger()->debug("body contact at t = {:.4f} s: {} exchanges, surfaces {:.4f} mm, residual penetration {:.3f} mm{}",
                  t1, r.exchanges, 1e3 * r.surface_residual, 1e3 * r.residual_penetration,
                  r.converged ? "" : " (not converged)");
}

}  // namespace

// The exchange of a touching cluster within a step (body_exchange.hpp): x, the cluster's surfaces the bodies are
// solved against (first: predicted), y = H(x), the surfaces they give. Converged when no vertex of y moved more
// than exchange_tolerance from x and the cluster's summed contact force changed by at most kForceChange since
// the previous exchange, or when no contact force acts and the bodies' final surfaces are apart by more than the
// margin (the solves did not feel x). After max_exchanges the last solve is kept, with a warning.
ExchangeRecord GroupStep::exchange_cluster(const std::vector<std::size_t>& cluster,
                                           const std::vector<RowMatrixX3d>& predicted, double t0, double h,
                                           std::vector<EffectSeconds>& seconds, bool threads) {
  constexpr double kForceChange = 0.02;  // relative
  constexpr double kForceFloor = 1e-3;   // [N] below which a summed contact force counts as none
  const double t1 = t0 + h;
  const std::size_t n = cluster.size();
  const ClusterExchangeLayout layout = cluster_exchange_layout(cluster, bodies_, contact_);
  Eigen::VectorXd x(layout.offset.back()), y(layout.offset.back());
  cluster_exchange_stack(
      layout, [&](std::size_t i) -> const RowMatrixX3d& { return predicted[cluster[i]]; }, x);
  std::vector<RowMatrixX3d> out(n), seen(n);
  auto gather = [&]() {
    for (std::size_t i = 0; i < n; ++i) out[i] = bodies_[cluster[i]]->world_surface();
    cluster_exchange_stack(
        layout, [&](std::size_t i) -> const RowMatrixX3d& { return out[i]; }, y);
  };
  gather();
  double force = cluster_force(cluster), previous_force = -1.0;
  ExchangeRecord r;
  r.t = t1;
  r.bodies = cluster;
  r.exchanges = 1;
  auto accelerator = std::make_unique<ExchangeAccelerator>(0.5);
  double best = std::numeric_limits<double>::infinity();
  int since_best = 0;
  bool penetration_known = false;
  for (;;) {
    r.surface_residual = cluster_exchange_largest_move(x, y);
    if (cluster_exchange_stalled((y - x).norm(), best, since_best)) {
      accelerator = std::make_unique<ExchangeAccelerator>(0.5);
      ++r.restarts;
    }
    r.force_change = previous_force < 0.0 ? 0.0 : std::abs(force - previous_force) / std::max(force, kForceFloor);
    if (r.surface_residual <= scene_.contact.exchange_tolerance && r.force_change <= kForceChange) {
      r.converged = true;
      break;
    }
    if (force < kForceFloor) {
      r.residual_penetration = cluster_penetration(cluster, out);
      penetration_known = true;
      if (r.residual_penetration < -contact_parameters(scene_.contact).margin) {  // apart: x was not felt
        r.converged = true;
        r.apart = true;
        break;
      }
    }
    if (r.exchanges >= scene_.contact.max_exchanges) break;
    x = accelerator->next(x, y);
    cluster_exchange_unstack(layout, x, seen);
    for (std::size_t i = 0; i < n; ++i) {
      restore_step_start(cluster[i]);
      see_bodies(
          cluster[i],
          [&](std::size_t o) -> const RowMatrixX3d& {
            return seen[static_cast<std::size_t>(std::find(cluster.begin(), cluster.end(), o) - cluster.begin())];
          },
          &cluster);  // every other body of the cluster is felt by body i, which has a potential
    }
    solve_bodies(cluster, t0, h, seconds, threads);
    gather();
    previous_force = force;
    force = cluster_force(cluster);
    penetration_known = false;
    ++r.exchanges;
  }
  if (!penetration_known) r.residual_penetration = cluster_penetration(cluster, out);
  r.residual_penetration = std::max(0.0, r.residual_penetration);
  cluster_exchange_log(r, cluster, bodies_, scene_.contact, t1);
  return r;
}

// The summed magnitude of the body-contact forces on the cluster's nodes [N].
double GroupStep::cluster_force(const std::vector<std::size_t>& cluster) const {
  double f = 0.0;
  for (std::size_t b : cluster)
    if (contact_[b].bodies) f += contact_[b].bodies->contact_force().rowwise().norm().sum();
  return f;
}

// The deepest point [m] (negative: the smallest gap) of the cluster bodies' candidate skin vertices inside the
// other cluster bodies' surfaces `world` (per cluster body); the body obstacles are left at those surfaces.
double GroupStep::cluster_penetration(const std::vector<std::size_t>& cluster, const std::vector<RowMatrixX3d>& world) {
  auto index_of = [&](std::size_t o) {
    return static_cast<std::size_t>(std::find(cluster.begin(), cluster.end(), o) - cluster.begin());
  };
  double deepest_point = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < cluster.size(); ++i) {
    const std::size_t b = cluster[i];
    BodyContact& c = contact_[b];
    if (!c.bodies) continue;
    see_bodies(
        b, [&](std::size_t o) -> const RowMatrixX3d& { return world[index_of(o)]; }, &cluster);
    std::vector<char> candidate(c.entry_of_node.size(), 0);
    for (int k : c.bodies->candidates()) candidate[static_cast<std::size_t>(c.bodies->nodes()[k])] = 1;
    const Rigid body_from_world = bodies_[b]->placement().inverse();
    const SceneBody& body = *bodies_[b];
    for (int v : body.layer().mesh->region_surface.vertices) {
      const int node = body.vertex_node()[static_cast<std::size_t>(v)];
      if (node < 0 || !candidate[static_cast<std::size_t>(node)]) continue;
      const Eigen::Vector3d local = body_from_world.R * world[i].row(v).transpose() + body_from_world.t;
      for (std::size_t k = 0; k < c.other.size(); ++k)
        if (index_of(static_cast<std::size_t>(c.other[k])) < cluster.size())
          deepest_point = std::max(deepest_point, -c.surfaces[k]->distance(local));
    }
  }
  return deepest_point;
}

}  // namespace sflsh::scene::detail
