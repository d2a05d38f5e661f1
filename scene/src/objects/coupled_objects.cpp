// The scene's free rigid objects inside one reduced body's Newton solve (coupled_objects.hpp).
#include "objects/coupled_objects.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace sflsh::scene::detail {

namespace {

/// The state in the frame p' = Rᵀ(p − t) of a placement world = R p + t.
RigidState to_frame(const Rigid& world_from_frame, const RigidState& world) {
  RigidState s;
  const Eigen::Matrix3d Rt = world_from_frame.R.transpose();
  s.placement.x = Rt * (world.placement.x - world_from_frame.t);
  s.placement.R = Rt * world.placement.R;
  s.velocity = Rt * world.velocity;
  s.angular_velocity = Rt * world.angular_velocity;
  return s;
}

RigidState to_world(const Rigid& world_from_frame, const RigidState& local) {
  RigidState s;
  s.placement.x = world_from_frame.R * local.placement.x + world_from_frame.t;
  s.placement.R = world_from_frame.R * local.placement.R;
  s.velocity = world_from_frame.R * local.velocity;
  s.angular_velocity = world_from_frame.R * local.angular_velocity;
  return s;
}

/// The nearest rotation (re-orthonormalized against round-off drift).
Eigen::Matrix3d orthonormal(const Eigen::Matrix3d& R) { return Eigen::Quaterniond(R).normalized().toRotationMatrix(); }

double bounding_radius(const RigidObject& r) { return r.bounding_radius(); }

}  // namespace

CoupledObjects::CoupledObjects(CoupledSetup setup) : setup_(std::move(setup)) {
  require(setup_.nodes.size() == setup_.node_stiffness.size(), "coupled objects: {} nodes, {} stiffnesses",
          setup_.nodes.size(), setup_.node_stiffness.size());
  require(setup_.objects.size() == setup_.friction.size(), "coupled objects: {} objects, {} friction coefficients",
          setup_.objects.size(), setup_.friction.size());
  setup_.parameters.validate();
  const Rigid body_from_world = setup_.world_from_body.inverse();
  setup_.gravity = body_from_world.R * setup_.gravity;  // in the body's frame from here on
  for (RigidObject* r : setup_.objects) {
    Object o;
    o.state = to_frame(setup_.world_from_body, r->state());
    o.samples = contact_samples(r->shape(), r->properties().area, setup_.parameters.stiffness);
    o.sample_factor.assign(o.samples.size(), 1.0);
    objects_.push_back(std::move(o));
  }
  candidate_of_entry_.assign(setup_.nodes.size(), -1);
  node_force_.assign(setup_.nodes.size(), Eigen::Vector3d::Zero());
  node_depth_.assign(setup_.nodes.size(), 0.0);
  near_.resize(objects_.size());
}

double CoupledObjects::node_stiffness(const Object& object, int entry) const {
  const auto it = object.node_factor.find(entry);
  return setup_.node_stiffness[static_cast<std::size_t>(entry)] * (it == object.node_factor.end() ? 1.0 : it->second);
}

double CoupledObjects::rigid_stiffness(const Object& object, int vertex) const {
  const auto it = object.rigid_factor.find(vertex);
  return setup_.rigid_stiffness[static_cast<std::size_t>(vertex)] *
         (it == object.rigid_factor.end() ? 1.0 : it->second);
}

void CoupledObjects::begin_substep(double t0, double dt, const RowMatrixX3d& p_start,
                                   const RowMatrixX3d& p_skinned_end) {
  const ScopedSeconds timer(seconds_);
  t0_ = t0;
  dt_ = dt;
  epsilon_ = setup_.parameters.slip_velocity * dt;
  const double t1 = t0 + dt;
  const Rigid body_from_world = setup_.world_from_body.inverse();
  posed_.clear();
  for (auto& [shape, motion] : setup_.obstacles) {
    const Pose world = motion->pose(t1);
    Pose local;
    local.rotation = body_from_world.R * world.rotation;
    local.translation = body_from_world.R * world.translation + body_from_world.t;
    shape->set_pose(local);
    posed_.push_back(shape.get());
  }
  if (!setup_.rigid_stiffness.empty()) {
    rigid_start_ = body_from_world.apply(setup_.rigid_positions(t0));
    rigid_end_ = body_from_world.apply(setup_.rigid_positions(t1));
  }
  // Candidates: nodes within reach of an object's bounding ball over the substep (the reach covers the object's
  // own motion at its current velocity, the skin's skinned motion and 2 cm for the elastic part).
  std::fill(candidate_of_entry_.begin(), candidate_of_entry_.end(), -1);
  candidates_.clear();
  std::vector<int> order;
  for (std::size_t o = 0; o < objects_.size(); ++o) {
    Object& object = objects_[o];
    Near& near = near_[o];
    near = {};
    const RigidState& s = object.state;
    const double radius = bounding_radius(*setup_.objects[o]);
    const double reach =
        radius + setup_.parameters.margin + dt * s.velocity.norm() + dt * s.angular_velocity.norm() * radius + 0.02;
    const Eigen::Vector3d centre = s.placement.x;
    for (Eigen::Index e = 0; e < p_start.rows(); ++e) {
      const Eigen::Vector3d a = p_start.row(e).transpose(), b = p_skinned_end.row(e).transpose();
      if (std::min((a - centre).norm(), (b - centre).norm()) > reach + (b - a).norm()) continue;
      int& c = candidate_of_entry_[static_cast<std::size_t>(e)];
      if (c < 0) {
        c = static_cast<int>(candidates_.size());
        candidates_.push_back(static_cast<int>(e));
      }
      near.candidates.push_back(c);
    }
    for (Eigen::Index v = 0; v < rigid_end_.rows(); ++v) {
      const Eigen::Vector3d a = rigid_start_.row(v).transpose(), b = rigid_end_.row(v).transpose();
      if (std::min((a - centre).norm(), (b - centre).norm()) > reach + (b - a).norm()) continue;
      near.rigid.push_back(static_cast<int>(v));
    }
    // Node factors of nodes that are no longer near return to 1 (as the body's potential does).
    for (auto it = object.node_factor.begin(); it != object.node_factor.end();)
      it = candidate_of_entry_[static_cast<std::size_t>(it->first)] < 0 ? object.node_factor.erase(it) : std::next(it);
  }
  p_start_.resize(static_cast<Eigen::Index>(candidates_.size()), 3);
  for (std::size_t c = 0; c < candidates_.size(); ++c)
    p_start_.row(static_cast<Eigen::Index>(c)) = p_start.row(candidates_[c]);
  for (std::size_t o = 0; o < objects_.size(); ++o) {
    Near& near = near_[o];
    const std::vector<Lagged>& lagged = objects_[o].lagged;
    for (std::size_t k = 0; k < lagged.size(); ++k) {
      int candidate = -1;
      if (lagged[k].kind == Kind::node) {
        candidate = candidate_of_entry_[static_cast<std::size_t>(lagged[k].id)];
        if (candidate < 0) continue;  // the node left: no friction from it
      }
      near.friction.push_back(static_cast<int>(k));
      near.friction_candidate.push_back(candidate);
    }
  }
}

double CoupledObjects::object_energy(std::size_t o, const ObjectFrame& frame, const RowMatrixX3d& P,
                                     reduced::CoupledDerivatives* d, bool with_hessian) const {
  const Object& object = objects_[o];
  const Near& near = near_[o];
  const RigidObjectParameters& prm = setup_.parameters;
  const RigidObject& rigid = *setup_.objects[o];
  const auto at = static_cast<Eigen::Index>(6 * o);
  Vector6d g = Vector6d::Zero();
  Matrix6d H = Matrix6d::Zero();
  Vector6d* gp = d ? &g : nullptr;
  Matrix6d* Hp = d && with_hessian ? &H : nullptr;
  double value = object_inertia(rigid.properties(), object.state, dt_, setup_.gravity, frame, gp, Hp);
  for (std::size_t s = 0; s < object.samples.size(); ++s) {
    RigidSample sample = object.samples[s];
    sample.stiffness *= object.sample_factor[s];
    for (const Obstacle* obstacle : posed_) value += sample_penalty(*obstacle, sample, prm.margin, frame, gp, Hp);
  }
  Vector9d g9;
  Matrix9d H9;
  // Soft skin nodes: derivatives in (p, y).
  auto add_node = [&](int c, const Vector9d& gv, const Matrix9d& Hv) {
    g += gv.tail<6>();
    d->node_gradient.row(c) += gv.head<3>().transpose();
    if (!with_hessian) return;
    H += Hv.bottomRightCorner<6, 6>();
    d->node_hessian[static_cast<std::size_t>(c)] += Hv.topLeftCorner<3, 3>();
    d->node_mixed.block<3, 6>(3 * c, at) += Hv.topRightCorner<3, 6>();
  };
  for (int c : near.candidates) {
    const int entry = candidates_[static_cast<std::size_t>(c)];
    g9.setZero();
    H9.setZero();
    const double u = point_penalty(rigid.shape(), P.row(c).transpose(), node_stiffness(object, entry), prm.margin,
                                   frame, d ? &g9 : nullptr, Hp ? &H9 : nullptr);
    value += u;
    if (d && u > 0.0) add_node(c, g9, H9);
  }
  // Skin carried by the skeleton: fixed points, derivatives in y only.
  for (int v : near.rigid) {
    g9.setZero();
    H9.setZero();
    const double u = point_penalty(rigid.shape(), rigid_end_.row(v).transpose(), rigid_stiffness(object, v), prm.margin,
                                   frame, d ? &g9 : nullptr, Hp ? &H9 : nullptr);
    value += u;
    if (d && u > 0.0) {
      g += g9.tail<6>();
      if (Hp) H += H9.bottomRightCorner<6, 6>();
    }
  }
  // Friction, lagged by one substep.
  const double mu = setup_.friction[o];
  if (mu > 0.0)
    for (std::size_t k = 0; k < near.friction.size(); ++k) {
      const Lagged& l = object.lagged[static_cast<std::size_t>(near.friction[k])];
      const int c = near.friction_candidate[k];
      Eigen::Vector3d p = Eigen::Vector3d::Zero(), p0 = Eigen::Vector3d::Zero();  // obstacles: fixed
      if (l.kind == Kind::node) {
        p = P.row(c).transpose();
        p0 = p_start_.row(c).transpose();
      } else if (l.kind == Kind::rigid) {
        p = rigid_end_.row(l.id).transpose();
        p0 = rigid_start_.row(l.id).transpose();
      }
      g9.setZero();
      H9.setZero();
      value += point_friction(l.contact, p, p0, mu, epsilon_, frame, d ? &g9 : nullptr, Hp ? &H9 : nullptr);
      if (!d) continue;
      if (l.kind == Kind::node) {
        add_node(c, g9, H9);
      } else {
        g += g9.tail<6>();
        if (Hp) H += H9.bottomRightCorner<6, 6>();
      }
    }
  if (d) {
    d->gradient.segment<6>(at) += g;
    if (with_hessian) d->hessian.block<6, 6>(at, at) += H;
  }
  return value;
}

double CoupledObjects::evaluate(const RowMatrixX3d& P, const Eigen::VectorXd& y, reduced::CoupledDerivatives* d,
                                bool with_hessian) const {
  const ScopedSeconds timer(seconds_);
  if (d) d->reset(P.rows(), size(), with_hessian);
  double value = 0.0;
  for (std::size_t o = 0; o < objects_.size(); ++o) {
    const ObjectFrame frame(objects_[o].state.placement, y.segment<6>(static_cast<Eigen::Index>(6 * o)));
    value += object_energy(o, frame, P, d, with_hessian);
  }
  return std::isfinite(value) ? value : std::numeric_limits<double>::infinity();
}

bool CoupledObjects::accept_substep(const RowMatrixX3d& P_end, const Eigen::VectorXd& y) {
  const ScopedSeconds timer(seconds_);
  const RigidObjectParameters& prm = setup_.parameters;
  bool accepted = true;
  for (std::size_t o = 0; o < objects_.size(); ++o) {
    Object& object = objects_[o];
    const Obstacle& shape = setup_.objects[o]->shape();
    const ObjectFrame frame(object.state.placement, y.segment<6>(static_cast<Eigen::Index>(6 * o)));
    bool stiffened = false;
    auto stiffen = [&](std::unordered_map<int, double>& factors, int id) {
      auto [it, fresh] = factors.emplace(id, 1.0);
      it->second *= prm.refinement_factor;
      stiffened = true;
    };
    for (int c : near_[o].candidates)
      if (point_gap(shape, P_end.row(c).transpose(), frame).phi < -prm.tolerance)
        stiffen(object.node_factor, candidates_[static_cast<std::size_t>(c)]);
    for (int v : near_[o].rigid)
      if (point_gap(shape, rigid_end_.row(v).transpose(), frame).phi < -prm.tolerance) stiffen(object.rigid_factor, v);
    for (std::size_t s = 0; s < object.samples.size(); ++s)
      for (const Obstacle* obstacle : posed_)
        if (sample_gap(*obstacle, object.samples[s], frame) < -prm.tolerance) {
          object.sample_factor[s] *= prm.refinement_factor;
          stiffened = true;
        }
    if (stiffened) ++object.report.refinements;
    accepted = accepted && !stiffened;
  }
  return accepted;
}

namespace {

/// A sample's penalty contact with an obstacle at the substep's end (body frame).
struct CoupledSampleContact {
  double energy = 0.0;                   ///< u [J]
  Vector6d gradient = Vector6d::Zero();  ///< ∂u/∂y
  double phi = 0.0;                      ///< the sample's gap [m]
  FrictionContact lagged;                ///< the friction contact it leaves to the next substep
};

/// A skin point's penalty contact with an object's shape at the substep's end (body frame).
struct CoupledPointContact {
  double energy = 0.0;                   ///< u [J]
  Vector9d gradient = Vector9d::Zero();  ///< ∂u/∂(p, y)
  PointGap gap;                          ///< φ, normal and closest point on the shape
  FrictionContact lagged;                ///< the friction contact it leaves to the next substep
};

/// Clears the contact forces and energy of an object's report before a substep's are summed into it.
void coupled_clear_contact_forces(RigidStepReport& r) {
  r.obstacle_force.setZero();
  r.surface_force.setZero();
  r.rigid_surface_force.setZero();
  r.surface_friction_force.setZero();
  r.contact_energy = 0.0;
}

/// The contact of `sample` (its stiffness factored in) with `obstacle` at the frame; nullopt when it does not touch.
std::optional<CoupledSampleContact> coupled_sample_contact(const Obstacle& obstacle, const RigidSample& sample,
                                                           double margin, const ObjectFrame& frame) {
  CoupledSampleContact c;
  c.energy = sample_penalty(obstacle, sample, margin, frame, &c.gradient, nullptr);
  if (!(c.energy > 0.0)) return std::nullopt;
  Eigen::Vector3d n;
  c.phi = sample_gap(obstacle, sample, frame, &n);
  c.lagged.point = sample.point - sample.radius * (frame.R.transpose() * n);
  c.lagged.normal = n;
  c.lagged.normal_force = sample.stiffness * (margin - c.phi);
  return c;
}

/// The contact of the skin point `p` of stiffness `k` [N/m] with `shape` at the frame; nullopt when it does not touch.
std::optional<CoupledPointContact> coupled_point_contact(const Obstacle& shape, const Eigen::Vector3d& p, double k,
                                                         double margin, const ObjectFrame& frame) {
  CoupledPointContact c;
  c.energy = point_penalty(shape, p, k, margin, frame, &c.gradient, nullptr);
  if (!(c.energy > 0.0)) return std::nullopt;
  c.gap = point_gap(shape, p, frame);
  c.lagged.point = c.gap.local_closest;
  c.lagged.normal = c.gap.normal;
  c.lagged.normal_force = k * (margin - c.gap.phi);
  return c;
}

/// Adds the friction of one lagged contact at the substep's end to the report (its work, its force on the object);
/// returns −(its force on the point p).
Eigen::Vector3d coupled_add_friction(const FrictionContact& contact, const Eigen::Vector3d& p,
                                     const Eigen::Vector3d& p0, double mu, double epsilon, const ObjectFrame& frame,
                                     RigidStepReport& r) {
  Vector9d g = Vector9d::Zero();
  r.friction_work += point_friction(contact, p, p0, mu, epsilon, frame, &g, nullptr);
  r.surface_friction_force -= g.segment<3>(3);
  return g.head<3>();
}

/// The new state (backward Euler): v = Δx/h, ω = θ/h since R R_nᵀ = exp([θ]×).
RigidState coupled_next_state(const ObjectFrame& frame, const Vector6d& yo, double dt) {
  RigidState next;
  next.placement.x = frame.x;
  next.placement.R = orthonormal(frame.R);
  next.velocity = yo.head<3>() / dt;
  next.angular_velocity = yo.tail<3>() / dt;
  return next;
}

}  // namespace

void CoupledObjects::commit_substep(const RowMatrixX3d& P_end, const Eigen::VectorXd& y) {
  const ScopedSeconds timer(seconds_);
  const RigidObjectParameters& prm = setup_.parameters;
  std::fill(node_force_.begin(), node_force_.end(), Eigen::Vector3d::Zero());
  std::fill(node_depth_.begin(), node_depth_.end(), 0.0);
  for (std::size_t o = 0; o < objects_.size(); ++o) {
    Object& object = objects_[o];
    const RigidObject& rigid = *setup_.objects[o];
    const Obstacle& shape = rigid.shape();
    const Vector6d yo = y.segment<6>(static_cast<Eigen::Index>(6 * o));
    const ObjectFrame frame(object.state.placement, yo);
    RigidStepReport& r = object.report;
    // Forces on the object at the substep's end: −∂u/∂Δx of each contact [N].
    coupled_clear_contact_forces(r);
    double penetration = 0.0;
    std::vector<Lagged> lagged;
    for (std::size_t s = 0; s < object.samples.size(); ++s) {
      RigidSample sample = object.samples[s];
      sample.stiffness *= object.sample_factor[s];
      for (const Obstacle* obstacle : posed_) {
        const std::optional<CoupledSampleContact> c = coupled_sample_contact(*obstacle, sample, prm.margin, frame);
        if (!c) continue;
        r.contact_energy += c->energy;
        r.obstacle_force -= c->gradient.head<3>();
        penetration = std::max(penetration, -c->phi);
        lagged.push_back(Lagged{Kind::obstacle, -1, c->lagged});
      }
    }
    auto touch = [&](const Eigen::Vector3d& p, double k, Kind kind, int id, bool soft) {
      const std::optional<CoupledPointContact> c = coupled_point_contact(shape, p, k, prm.margin, frame);
      if (!c) return false;
      r.contact_energy += c->energy;
      const Eigen::Vector3d f = -c->gradient.segment<3>(3);
      r.surface_force += f;
      if (!soft) r.rigid_surface_force += f;
      penetration = std::max(penetration, -c->gap.phi);
      if (kind == Kind::node) {
        node_force_[static_cast<std::size_t>(id)] -= c->gradient.head<3>();
        node_depth_[static_cast<std::size_t>(id)] = std::max(node_depth_[static_cast<std::size_t>(id)], -c->gap.phi);
      }
      lagged.push_back(Lagged{kind, id, c->lagged});
      return true;
    };
    std::unordered_map<int, double> node_factor, rigid_factor;  // kept only while touching
    for (int c : near_[o].candidates) {
      const int entry = candidates_[static_cast<std::size_t>(c)];
      if (touch(P_end.row(c).transpose(), node_stiffness(object, entry), Kind::node, entry, true))
        if (const auto it = object.node_factor.find(entry); it != object.node_factor.end()) node_factor.insert(*it);
    }
    for (int v : near_[o].rigid)
      if (touch(rigid_end_.row(v).transpose(), rigid_stiffness(object, v), Kind::rigid, v, false))
        if (const auto it = object.rigid_factor.find(v); it != object.rigid_factor.end()) rigid_factor.insert(*it);
    // Friction forces at the end: −∂D/∂Δx per lagged contact of this substep.
    const double mu = setup_.friction[o];
    r.friction_work = 0.0;
    if (mu > 0.0)
      for (std::size_t k = 0; k < near_[o].friction.size(); ++k) {
        const Lagged& l = object.lagged[static_cast<std::size_t>(near_[o].friction[k])];
        if (l.kind == Kind::obstacle) continue;
        const int c = near_[o].friction_candidate[k];
        const Eigen::Vector3d p = l.kind == Kind::node ? Eigen::Vector3d(P_end.row(c).transpose())
                                                       : Eigen::Vector3d(rigid_end_.row(l.id).transpose());
        const Eigen::Vector3d p0 = l.kind == Kind::node ? Eigen::Vector3d(p_start_.row(c).transpose())
                                                        : Eigen::Vector3d(rigid_start_.row(l.id).transpose());
        const Eigen::Vector3d g_p = coupled_add_friction(l.contact, p, p0, mu, epsilon_, frame, r);
        if (l.kind == Kind::node) node_force_[static_cast<std::size_t>(l.id)] -= g_p;
      }
    r.max_penetration = std::max(r.max_penetration, penetration);
    r.unresolved = r.unresolved || penetration > prm.tolerance;
    object.node_factor = std::move(node_factor);
    object.rigid_factor = std::move(rigid_factor);
    object.lagged = std::move(lagged);
    object.state = coupled_next_state(frame, yo, dt_);
  }
}

void CoupledObjects::save() {
  for (Object& o : objects_) o.report = RigidStepReport{};
  saved_ = objects_;
}

void CoupledObjects::restore() {
  objects_ = saved_;
  for (Object& o : objects_) ++o.report.halvings;
  saved_ = objects_;
}

double CoupledObjects::take_seconds() {
  const double s = seconds_;
  seconds_ = 0.0;
  return s;
}

std::vector<RigidStepReport> CoupledObjects::finish_step() {
  std::vector<RigidStepReport> out;
  for (std::size_t o = 0; o < objects_.size(); ++o) {
    Object& object = objects_[o];
    RigidStepReport r = object.report;
    // Forces to the world frame.
    const Eigen::Matrix3d& R = setup_.world_from_body.R;
    r.obstacle_force = R * r.obstacle_force;
    r.surface_force = R * r.surface_force;
    r.rigid_surface_force = R * r.rigid_surface_force;
    r.surface_friction_force = R * r.surface_friction_force;
    setup_.objects[o]->set_state(to_world(setup_.world_from_body, object.state));
    out.push_back(std::move(r));
    object.report = RigidStepReport{};
  }
  return out;
}

}  // namespace sflsh::scene::detail
