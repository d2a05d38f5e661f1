// Free rigid objects: mass properties, the step's energy terms against finite differences (inertia, obstacle
// contact, object–surface contact in the object's coordinates, friction), and a ball and a box dropped on
// a rigid plane: no energy gain, resting contact within the tolerance, spin kept by a frictionless ball.
#include "../material/finite_difference.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_object.hpp>

#include <gtest/gtest.h>

#include <memory>
#include <random>

namespace sflsh::scene {
namespace {

using testing::central_gradient;
using testing::central_jacobian;
using testing::relative_error;

/// The term's gradient with respect to z at the placement moved by z (not only at z = 0): the rotation part
/// is J_l(θ)ᵀ times the term's own gradient there (rigid_body.hpp), so its central differences at z = 0 test
/// the Hessian.
Vector6d gradient_at(const RigidTerm& term, const RigidPlacement& at, const Vector6d& z) {
  Vector6d g = Vector6d::Zero();
  term.evaluate(at.moved(z), &g, nullptr);
  g.tail<3>() = left_jacobian(z.tail<3>()).transpose() * g.tail<3>();
  return g;
}

/// Value, gradient and Hessian of a term at `at` against central differences. Steps of 1e-6 (m, rad) on
/// energies whose third derivatives are ≲ k·ℓ ~ 1e6 N/m·0.1 m: truncation h²/6·|f'''| ≲ 1e-7 relative to
/// gradients ~ 1e2; rounding ε|f|/h ~ 1e-10. 1e-5 leaves a margin for the curvature of box edges.
void expect_term_derivatives(const RigidTerm& term, const RigidPlacement& at, const char* what, double h = 1e-6) {
  Vector6d g = Vector6d::Zero();
  Matrix6d H = Matrix6d::Zero();
  const double value = term.evaluate(at, &g, &H);
  ASSERT_TRUE(std::isfinite(value)) << what;
  ASSERT_GT(g.norm(), 0.0) << what << ": the term must be active at the test placement";
  const Vector6d g_fd = central_gradient<6>(
      [&](const Vector6d& z) { return term.evaluate(at.moved(z), nullptr, nullptr); }, Vector6d::Zero().eval(), h);
  const Matrix6d H_fd =
      central_jacobian<6, 6>([&](const Vector6d& z) { return gradient_at(term, at, z); }, Vector6d::Zero().eval(), h);
  EXPECT_LT(relative_error(g_fd, g, 1e-8), 1e-5) << what << "\n" << g.transpose() << "\n" << g_fd.transpose();
  EXPECT_LT(relative_error(H_fd, H, 1e-8), 1e-5) << what << "\n" << H << "\n\n" << H_fd;
}

RigidPlacement tilted(const Eigen::Vector3d& x) {
  return {x, Eigen::AngleAxisd(0.5, Eigen::Vector3d(0.2, 1.0, -0.4).normalized()).toRotationMatrix()};
}

TEST(RigidBody, MassPropertiesOfAClosedMeshMatchTheBox) {
  // A box of half extents (0.1, 0.2, 0.3) as 12 outward triangles, its corner at the origin: the same mass and
  // second moment as box_properties, the centre at the half extents; exact up to round-off.
  const Eigen::Vector3d a(0.1, 0.2, 0.3);
  RowMatrixX3d V(8, 3);
  for (int i = 0; i < 8; ++i) V.row(i) << 2 * a.x() * (i & 1), 2 * a.y() * ((i >> 1) & 1), 2 * a.z() * ((i >> 2) & 1);
  RowMatrixX3i F(12, 3);
  F << 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6;
  Eigen::Vector3d centre;
  const RigidProperties m = mesh_properties(V, F, 700.0, centre);
  const RigidProperties b = box_properties(a, 700.0);
  EXPECT_NEAR(m.mass, b.mass, 1e-12);
  EXPECT_NEAR(m.volume, b.volume, 1e-14);
  EXPECT_NEAR(m.area, b.area, 1e-13);
  EXPECT_LT((centre - a).norm(), 1e-14);
  EXPECT_LT((m.second_moment - b.second_moment).norm(), 1e-12 * b.second_moment.norm());
  // Inward triangles enclose a negative volume: refused.
  RowMatrixX3i inward = F;
  inward.col(1).swap(inward.col(2));
  EXPECT_THROW(mesh_properties(V, inward, 700.0, centre), Error);
}

TEST(RigidBody, MassPropertiesOfTheShapes) {
  // Sphere: I = 2/5 m r²; box: I_xx = m (b² + c²)/3 with half extents; capsule without length = sphere.
  const RigidProperties s = sphere_properties(0.1, 1000.0);
  EXPECT_NEAR(s.mass, 1000.0 * 4.0 / 3.0 * EIGEN_PI * 1e-3, 1e-12);
  EXPECT_NEAR(s.inertia()(0, 0), 0.4 * s.mass * 0.01, 1e-14);
  const RigidProperties b = box_properties(Eigen::Vector3d(0.1, 0.2, 0.3), 500.0);
  EXPECT_NEAR(b.mass, 500.0 * 8 * 0.006, 1e-12);
  EXPECT_NEAR(b.inertia()(0, 0), b.mass * (0.04 + 0.09) / 3.0, 1e-12);
  const RigidProperties c0 = capsule_properties(0.1, 0.0, 1000.0);
  EXPECT_NEAR((c0.second_moment - s.second_moment).norm(), 0.0, 1e-14);
  // Capsule against a midpoint-rule integration over its bounding box (200³ cells of 1 mm: the boundary
  // cells give a relative error ~ cell/radius ~ 1e-2; 2e-2 is the bound).
  const double r = 0.05, L = 0.1;
  const Capsule capsule(r, L);
  const RigidProperties c = capsule_properties(r, L, 1.0);
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  double m = 0.0;
  const int n = 100;
  const double dx = 2 * r / n, dz = 2 * (L + r) / (2 * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < 2 * n; ++k) {
        const Eigen::Vector3d q(-r + (i + 0.5) * dx, -r + (j + 0.5) * dx, -L - r + (k + 0.5) * dz);
        if (capsule.local_distance(q, nullptr, nullptr) > 0.0) continue;
        m += dx * dx * dz;
        J += dx * dx * dz * q * q.transpose();
      }
  EXPECT_NEAR(c.mass, m, 2e-2 * m);
  EXPECT_LT(relative_error(J, c.second_moment), 2e-2);
  EXPECT_THROW(sphere_properties(-0.1, 1000.0), Error);
  EXPECT_THROW(box_properties(Eigen::Vector3d(0.1, 0.0, 0.1), 1000.0), Error);
  EXPECT_THROW(s.with_mass(0.0), Error);
}

TEST(RigidBody, RotationExpLogAndLeftJacobian) {
  const Eigen::Vector3d theta(0.3, -0.7, 0.2);
  EXPECT_LT((rotation_log(rotation_exp(theta)) - theta).norm(), 1e-12);
  const Eigen::Matrix3d R = rotation_exp(theta);
  EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  // d/dε exp(θ + ε) exp(θ)ᵀ = [J_l ε]× (central differences of 1e-6: error ~ 1e-12 / 1e-6).
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d e = 1e-6 * Eigen::Vector3d::Unit(a);
    const Eigen::Matrix3d dR = (rotation_exp(theta + e) - rotation_exp(theta - e)) / 2e-6 * R.transpose();
    EXPECT_LT((dR - hat(left_jacobian(theta).col(a))).norm(), 1e-8);
  }
}

TEST(RigidTerms, InertiaMatchesFiniteDifferences) {
  RigidProperties p = box_properties(Eigen::Vector3d(0.1, 0.05, 0.2), 800.0);
  RigidState start;
  start.placement = tilted(Eigen::Vector3d(0.1, 0.3, -0.2));
  start.velocity = Eigen::Vector3d(0.5, -1.0, 0.2);
  start.angular_velocity = Eigen::Vector3d(2.0, -1.0, 3.0);
  const RigidInertiaTerm term(p, start, 1.0 / 120, Eigen::Vector3d(0, -9.81, 0));
  // Away from the minimum so that both gradient parts are non-zero.
  const RigidPlacement at = start.placement.moved((Vector6d() << 0.01, -0.02, 0.005, 0.05, -0.1, 0.03).finished());
  expect_term_derivatives(term, at, "inertia");
}

TEST(RigidTerms, ObstacleContactMatchesFiniteDifferences) {
  HalfSpace ground(Eigen::Vector3d::UnitY(), 0.0);
  Sphere bump(0.3);
  bump.set_pose({Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.4, -0.25, 0.0)});
  const Box box(Eigen::Vector3d(0.1, 0.05, 0.08));
  const RigidObstacleContactTerm on_ground(contact_samples(box, 0.1, 1e7), {&ground, &bump}, 1e-3);
  expect_term_derivatives(on_ground, tilted(Eigen::Vector3d(0.2, 0.07, 0.0)), "box samples on a plane and a sphere");
  const RigidObstacleContactTerm ball(contact_samples(Sphere(0.06), 0.05, 1e7), {&ground}, 1e-3);
  expect_term_derivatives(ball, tilted(Eigen::Vector3d(0.0, 0.0595, 0.0)), "a ball on a plane");
}

TEST(RigidTerms, ObjectSurfaceContactMatchesFiniteDifferences) {
  // Points of a surface inside each shape's margin (off the shapes' non-smooth sets).
  const std::vector<Eigen::Vector3d> points = {{0.0, 0.0605, 0.0}, {0.02, 0.0598, 0.01}, {-0.03, 0.0601, 0.02}};
  const std::vector<double> k = {2000.0, 3000.0, 2500.0};
  const RigidPlacement at = tilted(Eigen::Vector3d(0.0, 0.0, 0.0));
  // Place each point just inside the shape's surface along its local normal.
  auto near_surface = [&](const Obstacle& shape) {
    std::vector<Eigen::Vector3d> out;
    for (const Eigen::Vector3d& p : points) {
      Eigen::Vector3d n;
      const Eigen::Vector3d q = at.R.transpose() * (p - at.x);
      const double phi = shape.local_distance(q, &n, nullptr);
      out.push_back(at.to_world(q - (phi + 4e-4) * n));  // 0.4 mm inside
    }
    return out;
  };
  const Sphere sphere(0.06);
  const Box box(Eigen::Vector3d(0.05, 0.06, 0.04));
  const Capsule capsule(0.04, 0.05);
  for (const Obstacle* shape : std::initializer_list<const Obstacle*>{&sphere, &box, &capsule}) {
    const ObjectSurfaceContactTerm term(*shape, near_surface(*shape), k, 1e-3);
    expect_term_derivatives(term, at, "object–surface contact");
  }
}

TEST(RigidTerms, FrictionMatchesFiniteDifferencesWhenStickingAndSliding) {
  const RigidPlacement start = tilted(Eigen::Vector3d(0.0, 0.06, 0.0));
  std::vector<FrictionContact> contacts = {
      {Eigen::Vector3d(0.0, -0.06, 0.0), Eigen::Vector3d(1e-4, 0.0, 0.0), Eigen::Vector3d::UnitY(), 20.0},
      {Eigen::Vector3d(0.03, -0.05, 0.01), Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 1.0, 0.0).normalized(), 5.0}};
  const double epsilon = 1e-3 / 120;  // ε_v h
  const RigidFrictionTerm friction(contacts, start, 0.5, epsilon);
  // Sliding: slip of ~1 mm ≫ ε; sticking: slip of ~1e-6 m < ε (the smoothed part f0).
  expect_term_derivatives(friction, start.moved((Vector6d() << 1e-3, 0, 5e-4, 0.0, 0.01, 0.02).finished()), "sliding");
  std::vector<FrictionContact> still = contacts;
  for (auto& c : still) c.other_displacement.setZero();
  const RigidFrictionTerm sticking(still, start, 0.5, epsilon);
  // Steps of 1e-9 m: f0''' ~ 2/ε² ~ 3e10 1/m² makes the truncation h²/ε² ~ 1e-8 relative; rounding
  // ε_mach |D| / h ~ 1e-16 · 1e-4 J / 1e-9 m ~ 1e-11 N against gradients ~ 1 N.
  expect_term_derivatives(sticking, start.moved((Vector6d() << 2e-6, 0, -1e-6, 0.0, 1e-5, 0.0).finished()), "sticking",
                          1e-9);
}

TEST(RigidTerms, FrictionForcesPerContactSumToMinusTheGradient) {
  // The per-contact forces (what the other side takes the opposite of) add up to −∂D/∂x, sliding and sticking.
  const RigidPlacement start = tilted(Eigen::Vector3d(0.0, 0.06, 0.0));
  const std::vector<FrictionContact> contacts = {
      {Eigen::Vector3d(0.0, -0.06, 0.0), Eigen::Vector3d(1e-4, 0.0, 0.0), Eigen::Vector3d::UnitY(), 20.0, 7},
      {Eigen::Vector3d(0.03, -0.05, 0.01), Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 1.0, 0.0).normalized(), 5.0}};
  const RigidFrictionTerm friction(contacts, start, 0.5, 1e-3 / 120);
  for (const Vector6d& z : {(Vector6d() << 1e-3, 0, 5e-4, 0.0, 0.01, 0.02).finished(),
                            (Vector6d() << 2e-6, 0, -1e-6, 0.0, 1e-5, 0.0).finished()}) {
    const RigidPlacement at = start.moved(z);
    Vector6d gradient = Vector6d::Zero();
    friction.evaluate(at, &gradient, nullptr);
    const std::vector<Eigen::Vector3d> forces = friction.forces(at);
    ASSERT_EQ(forces.size(), 2u);
    EXPECT_GT(forces[0].norm(), 0.0);
    EXPECT_LT((forces[0] + forces[1] + gradient.head<3>()).norm(), 1e-12 * (1.0 + gradient.norm()));
  }
  EXPECT_EQ(friction.contacts()[0].source, 7);
  EXPECT_EQ(friction.contacts()[1].source, -1);
}

// A 2 kg ball (r = 6 cm) dropped 10 cm onto the ground at 1/120 s, 3 s: the energy E = T + V + penalty
// never exceeds its start (plus 1e-9 J of round-off), it comes to rest and stays within the 1 mm tolerance.
struct DropResult {
  double max_gain = -1e300;          ///< max_t E(t) − E(0) [J]
  double max_step_gain = -1e300;     ///< max_n E_{n+1} − E_n [J]
  double resting_penetration = 0.0;  ///< over the last 2 s [m]
  double final_speed = 0.0;
  double max_penetration = 0.0;
  RigidState final_state;
};

DropResult drop(RigidObject& object, const Obstacle& ground, int steps, double h, int resting_from) {
  DropResult out;
  double e0 = object.kinetic() + object.potential(), previous = e0;
  for (int n = 0; n < steps; ++n) {
    const RigidStepReport r = object.step(h, {&ground}, {});
    const double e = object.kinetic() + object.potential() + r.contact_energy;
    out.max_gain = std::max(out.max_gain, e - e0);
    out.max_step_gain = std::max(out.max_step_gain, e - previous);
    previous = e;
    out.max_penetration = std::max(out.max_penetration, r.max_penetration);
    if (n >= resting_from) out.resting_penetration = std::max(out.resting_penetration, r.max_penetration);
  }
  out.final_state = object.state();
  out.final_speed = object.state().velocity.norm();
  return out;
}

TEST(RigidObject, BallDroppedOnAPlaneNeverGainsEnergyAndRestsWithinTolerance) {
  const HalfSpace ground(Eigen::Vector3d::UnitY(), 0.0);
  for (const double friction : {0.0, 0.5}) {
    RigidState start;
    start.placement.x = Eigen::Vector3d(0.0, 0.06 + 0.10, 0.0);
    start.velocity = Eigen::Vector3d(0.3, 0.0, 0.0);  // and sideways: friction makes it roll
    RigidObjectParameters parameters;
    parameters.friction = friction;
    RigidObject ball("ball", std::make_shared<Sphere>(0.06), sphere_properties(0.06, 1000.0).with_mass(2.0), start,
                     Eigen::Vector3d(0, -9.81, 0), parameters);
    const double h = 1.0 / 120;
    const DropResult r = drop(ball, ground, 360, h, 120);  // 3 s; the last 2 s at rest
    EXPECT_LE(r.max_gain, 1e-9) << "μ = " << friction;
    // 1 mm: the contact tolerance (the default of RigidObjectParameters).
    EXPECT_LE(r.resting_penetration, parameters.tolerance) << "μ = " << friction;
    EXPECT_LE(r.max_penetration, parameters.tolerance) << "μ = " << friction;
    EXPECT_NEAR(r.final_state.placement.x.y(), 0.06, 1.5e-3) << "μ = " << friction;
    EXPECT_LT(std::abs(r.final_state.velocity.y()), 1e-3) << "μ = " << friction;
    if (friction > 0.0) {
      // Rolling without slipping: v = ω × r, so ω_z = −v_x / r (within 5% once it rolls).
      const double v = r.final_state.velocity.x(), w = r.final_state.angular_velocity.z();
      EXPECT_GT(v, 0.05);
      EXPECT_NEAR(w, -v / 0.06, 0.05 * std::abs(v / 0.06));
    } else {
      EXPECT_NEAR(r.final_state.velocity.x(), 0.3, 1e-6);  // nothing acts sideways
      EXPECT_LT(r.final_state.angular_velocity.norm(), 1e-9);
    }
  }
}

TEST(RigidObject, RigidPointsShareOfTheSurfaceForceIsReportedApart) {
  // A ball pressed onto a 2 cm grid of surface points, centred between the columns x = 0 and x = 0.02: with
  // every point rigid the rigid share is the whole surface force; with the columns x ≤ 0 rigid it is half of it
  // (the grid is symmetric about x = 0.01).
  SurfacePoints grid;
  for (int i = -6; i <= 6; ++i)
    for (int k = -6; k <= 6; ++k) {
      const Eigen::Vector3d p(0.02 * i, 0.0, 0.02 * k);
      grid.start.push_back(p);
      grid.end.push_back(p);
      grid.stiffness.push_back(2000.0);
      grid.rigid.push_back(i <= 0 ? 1 : 0);
    }
  for (const bool all_rigid : {true, false}) {
    SurfacePoints points = grid;
    if (all_rigid) points.rigid.assign(points.rigid.size(), 1);
    RigidState start;
    start.placement.x = Eigen::Vector3d(0.01, 0.0605, 0.0);
    RigidObject ball("ball", std::make_shared<Sphere>(0.06), sphere_properties(0.06, 1000.0).with_mass(2.0), start,
                     Eigen::Vector3d(0, -9.81, 0), RigidObjectParameters{});
    // Released 0.5 mm above the grid's contact margin: the first steps press it in.
    RigidStepReport r;
    for (int s = 0; s < 3 && !(r.surface_force.y() > 1.0); ++s) r = ball.step(1.0 / 120, {}, {points});
    ASSERT_GT(r.surface_force.y(), 1.0) << "the grid pushes the ball";
    if (all_rigid) {
      EXPECT_LT((r.rigid_surface_force - r.surface_force).norm(), 1e-9 * r.surface_force.norm());
    } else {
      EXPECT_NEAR(r.rigid_surface_force.y(), 0.5 * r.surface_force.y(), 1e-3 * r.surface_force.y());
    }
  }
}

TEST(RigidObject, BoxDroppedTiltedOnAPlaneSettlesFlatWithoutGainingEnergy) {
  const HalfSpace ground(Eigen::Vector3d::UnitY(), 0.0);
  RigidState start;
  start.placement.x = Eigen::Vector3d(0.0, 0.15, 0.0);
  start.placement.R = rotation_exp(Eigen::Vector3d(0.3, 0.0, 0.2));
  start.angular_velocity = Eigen::Vector3d(0.0, 1.0, 0.0);
  RigidObjectParameters parameters;
  RigidObject box("box", std::make_shared<Box>(Eigen::Vector3d(0.1, 0.04, 0.075)),
                  box_properties(Eigen::Vector3d(0.1, 0.04, 0.075), 1000.0).with_mass(3.0), start,
                  Eigen::Vector3d(0, -9.81, 0), parameters);
  const DropResult r = drop(box, ground, 360, 1.0 / 120, 120);
  EXPECT_LE(r.max_gain, 1e-9);
  EXPECT_LE(r.resting_penetration, parameters.tolerance);
  // Flat on its largest face: the local y axis vertical, the centre a half height (4 cm) above the ground.
  EXPECT_GT(std::abs(r.final_state.placement.R(1, 1)), 0.999);
  EXPECT_NEAR(r.final_state.placement.x.y(), 0.04, 1.5e-3);
  EXPECT_LT(r.final_speed, 1e-3);
}

TEST(RigidObject, FreeSpinKeepsItsAngularVelocityAndEnergy) {
  // Torque-free spin of a box about a non-principal axis: R_{n+1} = exp(h[ω]×) R_n minimizes the inertia
  // term, so ω stays and T = ½ ωᵀ R I Rᵀ ω is constant. The Newton tolerance (~1e-9 m over ℓ ~ 0.07 m, per
  // step of 1/120 s) bounds the error of ω by ~1e-6 rad/s per step; 1e-6 relative is the bound.
  RigidState start;
  start.angular_velocity = Eigen::Vector3d(1.0, 2.0, 4.0);
  RigidObject box("box", std::make_shared<Box>(Eigen::Vector3d(0.1, 0.04, 0.075)),
                  box_properties(Eigen::Vector3d(0.1, 0.04, 0.075), 1000.0), start, Eigen::Vector3d::Zero(), {});
  const double e0 = box.kinetic();
  for (int n = 0; n < 120; ++n) {
    box.step(1.0 / 120, {}, {});
    EXPECT_LE(box.kinetic(), e0 * (1.0 + 1e-6));
  }
  EXPECT_LT((box.state().angular_velocity - start.angular_velocity).norm(), 1e-6 * start.angular_velocity.norm());
  EXPECT_GE(box.kinetic(), e0 * (1.0 - 1e-6));
}

TEST(RigidObject, BadParametersAreRefusedWithOneLine) {
  RigidObjectParameters bad;
  bad.friction = -1.0;
  try {
    RigidObject("ball", std::make_shared<Sphere>(0.06), sphere_properties(0.06, 1000.0), {}, Eigen::Vector3d::Zero(),
                bad);
    FAIL() << "negative friction accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("friction"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_THROW(RigidObject("m", std::make_shared<HalfSpace>(Eigen::Vector3d::UnitY(), 0.0),
                           sphere_properties(0.06, 1000.0), {}, Eigen::Vector3d::Zero(), {}),
               Error);
  RigidState nan;
  nan.velocity.x() = std::nan("");
  EXPECT_THROW(RigidObject("ball", std::make_shared<Sphere>(0.06), sphere_properties(0.06, 1000.0), nan,
                           Eigen::Vector3d::Zero(), {}),
               Error);
}

}  // namespace
}  // namespace sflsh::scene
