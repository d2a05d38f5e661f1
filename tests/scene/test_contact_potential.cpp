// The contact penalty: derivatives, PSD Hessian, broad phase, refinement, a 1-dof Newton toy and a
// free object resting on nodes.
#include "scene_test_support.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/scene/contact_potential.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <memory>

namespace sflsh::scene {
namespace {

using meshing::RowMatrixX3d;
using testing::central_gradient;
using testing::central_jacobian;
using testing::relative_error;

RowMatrixX3d rows(std::initializer_list<Eigen::Vector3d> points) {
  RowMatrixX3d m(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const auto& p : points) m.row(i++) = p.transpose();
  return m;
}

Pose tilted_contact_pose() {
  Pose pose;
  pose.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  pose.translation = Eigen::Vector3d(0.05, 0.0, -0.02);
  return pose;
}

/// One node near `shape`, positions p (world) where every term is active and φ is C² (points ≥ 1 mm
/// from φ = δ and from the shapes' non-smooth sets). Steps of h = 1e-7 m: near a box edge or a capsule
/// the curvature is up to 1/φ ~ 1e3 1/m, so the truncation error h²|∇⁴u|/6 ~ k h²/φ³ stays ≲ 1e-8
/// relative, and rounding ε|∇u|/h ~ 1e-8 N/m against Hessians ~ 1e3 N/m; 1e-6 leaves margin.
void expect_potential_derivatives(const std::shared_ptr<Obstacle>& shape, const std::vector<Eigen::Vector3d>& points) {
  ContactParameters parameters;
  parameters.project_hessian = false;
  for (const Eigen::Vector3d& p : points) {
    ContactPotential potential({7}, {}, {{shape, nullptr}}, parameters);
    ASSERT_TRUE(potential.begin_substep(0.0, 0.01, rows({p}), rows({p})));
    ASSERT_EQ(potential.candidates(), std::vector<int>{0});
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    const double u = potential.evaluate(0, p, &g, &H);
    ASSERT_GT(u, 0.0) << p.transpose();
    const double h = 1e-7;
    const Eigen::Vector3d g_fd =
        central_gradient([&](const Eigen::Vector3d& x) { return potential.evaluate(0, x, nullptr, nullptr); }, p, h);
    const Eigen::Matrix3d H_fd = central_jacobian(
        [&](const Eigen::Vector3d& x) {
          Eigen::Vector3d gx;
          potential.evaluate(0, x, &gx, nullptr);
          return gx;
        },
        p, h);
    EXPECT_LT(relative_error(g, g_fd, 1e-3), 1e-6) << p.transpose();
    EXPECT_LT(relative_error(H, H_fd, 1e-3), 1e-6) << p.transpose() << "\n" << H << "\nfd\n" << H_fd;
  }
}

TEST(ContactPotential, GradientAndHessianMatchFiniteDifferences) {
  auto plane = std::make_shared<HalfSpace>(Eigen::Vector3d(0.2, 0.1, 1.0), 0.0);
  plane->set_pose(tilted_contact_pose());
  expect_potential_derivatives(plane, {plane->pose().to_world({0.1, 0.0, -0.024})});
  auto sphere = std::make_shared<Sphere>(0.1);
  sphere->set_pose(tilted_contact_pose());
  expect_potential_derivatives(sphere, {sphere->pose().to_world({0.0, 0.0995, 0.0}),
                                        sphere->pose().to_world(Eigen::Vector3d(1, 1, 1).normalized() * 0.095)});
  auto box = std::make_shared<Box>(Eigen::Vector3d(0.1, 0.05, 0.08));
  box->set_pose(tilted_contact_pose());
  expect_potential_derivatives(box, {box->pose().to_world({0.1006, 0.0, 0.0804}),  // edge region, outside
                                     box->pose().to_world({0.02, 0.047, 0.0})});   // inside
  auto capsule = std::make_shared<Capsule>(0.05, 0.1);
  capsule->set_pose(tilted_contact_pose());
  expect_potential_derivatives(
      capsule, {capsule->pose().to_world({0.0498, 0.0, 0.02}), capsule->pose().to_world({0.0, 0.0, 0.1499})});
}

// With projection on the Hessian is PSD; at a convex obstacle it is the Gauss–Newton k ∇φ∇φᵀ, at a
// flat one the exact Hessian.
TEST(ContactPotential, ProjectedHessianIsPsdAndGaussNewtonOnConvexShapes) {
  auto sphere = std::make_shared<Sphere>(0.1);
  ContactPotential potential({0, 3}, {1e-4, 4e-4}, {{sphere, nullptr}});
  const RowMatrixX3d p = rows({{0.0, 0.0, 0.098}, {0.0, 0.097, 0.0}});
  ASSERT_TRUE(potential.begin_substep(0.0, 0.01, p, p));
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    potential.evaluate(k, p.row(k).transpose(), &g, &H);
    const Eigen::Vector3d n = p.row(k).normalized().transpose();
    const double stiffness = potential.node_stiffness(k);
    EXPECT_NEAR(stiffness, 1e7 * (k == 0 ? 1e-4 : 4e-4), 1e-9);
    EXPECT_LT((H - stiffness * n * n.transpose()).norm(), 1e-9 * stiffness);
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(H).eigenvalues().minCoeff(), -1e-9 * stiffness);
    // −∇u pushes out along the normal with k (δ − φ).
    const double phi = p.row(k).norm() - 0.1;
    EXPECT_LT((-g - stiffness * (1e-3 - phi) * n).norm(), 1e-12 * stiffness);
  }
  EXPECT_EQ(potential.evaluate(0, {0.0, 0.0, 0.2}, nullptr, nullptr), 0.0);  // beyond δ: nothing
}

// Far nodes are dropped by the broad phase and cost no narrow-phase work; an obstacle far from every
// node costs no distance query at all.
TEST(ContactPotential, BroadPhaseDropsFarNodes) {
  auto near_sphere = std::make_shared<Sphere>(0.1);
  auto far_box = std::make_shared<Box>(Eigen::Vector3d::Constant(0.1));
  Pose far;
  far.translation = {50.0, 0.0, 0.0};
  far_box->set_pose(far);
  std::vector<int> nodes;
  RowMatrixX3d p(400, 3);
  for (int i = 0; i < 400; ++i) {
    nodes.push_back(i);
    // 10 nodes on a ring 5 mm outside the sphere, the rest 1–4 m away.
    p.row(i) = i < 10 ? Eigen::RowVector3d(0.105 * std::cos(0.3 * i), 0.105 * std::sin(0.3 * i), 0.0)
                      : Eigen::RowVector3d(1.0 + 0.01 * i, 0.5, 0.0);
  }
  ContactPotential potential(nodes, {}, {{near_sphere, nullptr}, {far_box, nullptr}});
  EXPECT_EQ(potential.stats().broad_phase_passes, 0);
  ASSERT_TRUE(potential.begin_substep(0.0, 0.01, p, p));
  EXPECT_EQ(potential.candidates().size(), 10u);
  for (int c : potential.candidates()) EXPECT_LT(c, 10);
  ContactStats s = potential.stats();
  EXPECT_EQ(s.broad_phase_passes, 1);
  EXPECT_EQ(s.candidates, 10);
  EXPECT_EQ(s.broad_phase_queries, 2 * 10);  // only the nodes inside the sphere's box (+ reach)
  EXPECT_EQ(s.narrow_phase_evaluations, 0);
  for (std::size_t c = 0; c < potential.candidates().size(); ++c)
    potential.evaluate(static_cast<int>(c), p.row(potential.candidates()[c]).transpose(), nullptr, nullptr);
  EXPECT_EQ(potential.stats().narrow_phase_evaluations, 10);  // one obstacle each: not the far box

  // Everything far: idle, and only box tests ran.
  RowMatrixX3d q = p.array() + 10.0;
  potential.reset_stats();
  EXPECT_FALSE(potential.begin_substep(0.01, 0.01, q, q));
  EXPECT_TRUE(potential.candidates().empty());
  s = potential.stats();
  EXPECT_EQ(s.broad_phase_queries, 0);
  EXPECT_EQ(s.candidates, 0);
  // A node moving fast towards the sphere is a candidate from its skinned end position.
  RowMatrixX3d end = q;
  end.row(20) << 0.0, 0.0, 0.12;
  EXPECT_TRUE(potential.begin_substep(0.02, 0.01, q, end));
  EXPECT_EQ(potential.candidates(), std::vector<int>{20});
  // evaluate() takes the index into candidates(): candidate 0 is entry 20.
  EXPECT_GT(potential.evaluate(0, {0.0, 0.0, 0.0995}, nullptr, nullptr), 0.0);
}

// A node 5 mm deep is rejected (tolerance 1 mm) and gets ×4 stiffness; after max_refinements the substep is
// refused for good: counted as unresolved, with one line naming the obstacle, the node and the time, and nothing
// committed. A substep within the tolerance is then accepted with its forces.
TEST(ContactPotential, AcceptRejectsTooDeepNodesRaisesStiffnessAndThenRefusesForGood) {
  auto plane = std::make_shared<HalfSpace>(Eigen::Vector3d::UnitZ(), 0.0);
  ContactParameters parameters;
  parameters.max_refinements = 2;
  ContactPotential potential({0, 1}, {}, {{plane, nullptr, "object 'floor'"}}, parameters);
  const RowMatrixX3d p = rows({{0.0, 0.0, -0.005}, {0.1, 0.0, -0.0005}});
  const double k0 = potential.node_stiffness(0);
  ASSERT_TRUE(potential.begin_substep(0.0, 0.01, p, p));
  ASSERT_EQ(potential.candidates().size(), 2u);
  EXPECT_FALSE(potential.accept_substep(p));
  EXPECT_TRUE(potential.unresolved().empty());  // a refinement, not a refusal
  EXPECT_DOUBLE_EQ(potential.node_stiffness(0), 4.0 * k0);
  EXPECT_DOUBLE_EQ(potential.node_stiffness(1), k0);  // within tolerance: unchanged
  EXPECT_EQ(potential.stats().refinements, 1);
  ASSERT_TRUE(potential.begin_substep(0.0, 0.01, p, p));  // the retry keeps the raised stiffness
  EXPECT_DOUBLE_EQ(potential.node_stiffness(0), 4.0 * k0);
  EXPECT_FALSE(potential.accept_substep(p));
  EXPECT_FALSE(potential.accept_substep(p));  // max_refinements reached: refused for good
  const std::string why = potential.unresolved();
  EXPECT_NE(why.find("object 'floor'"), std::string::npos) << why;
  EXPECT_NE(why.find("skin node 0"), std::string::npos) << why;
  EXPECT_NE(why.find("5.00 mm"), std::string::npos) << why;
  EXPECT_NE(why.find("t = 0.01"), std::string::npos) << why;
  ContactStats s = potential.stats();
  EXPECT_EQ(s.refinements, 2);
  EXPECT_EQ(s.unresolved, 1);
  EXPECT_EQ(s.accepted, 0);
  EXPECT_EQ(s.max_penetration, 0.0);  // nothing committed
  EXPECT_EQ(potential.contact_force().cwiseAbs().maxCoeff(), 0.0);
  // The ladder's smaller substep from the same start, now within the tolerance: accepted with its forces.
  const RowMatrixX3d q = rows({{0.0, 0.0, -0.0008}, {0.1, 0.0, -0.0005}});
  ASSERT_TRUE(potential.begin_substep(0.0, 0.005, q, q));
  EXPECT_TRUE(potential.accept_substep(q));
  EXPECT_TRUE(potential.unresolved().empty());
  s = potential.stats();
  EXPECT_EQ(s.accepted, 1);
  EXPECT_NEAR(s.max_penetration, 0.0008, 1e-15);
  const double k = potential.node_stiffness(0);  // the raised stiffness is kept
  EXPECT_DOUBLE_EQ(k, 16.0 * k0);
  EXPECT_NEAR(potential.contact_force()(0, 2), k * 0.0018, 1e-9);
  EXPECT_NEAR(potential.obstacle_force(0).z(), -(k * 0.0018 + k0 * 0.0015), 1e-9);
  EXPECT_GT(s.seconds, 0.0);
}

// 1-dof toy: a node of mass m held at z = 0 by a spring k_s, pressed by a plane (occupying z > s(t))
// that moves from s = +5 mm to s = −10 mm and holds. Backward Euler with a tiny Newton loop drives the
// potential as an integrator would. With the default k = 2250 N/m the equilibrium penetration is
// k_s (δ − s)/(k + k_s) − δ ≈ 5.3 mm > 1 mm (1.75 mm at 4k, −0.15 mm at 16k): refined until below tolerance,
// and the final state is the analytic equilibrium z = k (s − δ)/(k + k_s) of the raised stiffness.
TEST(ContactPotential, SpringPressedByAPlaneConvergesBelowTolerance) {
  const double m = 1e-3, k_spring = 3000.0, dt = 0.01;
  auto plane = std::make_shared<HalfSpace>(Eigen::Vector3d(0.0, 0.0, -1.0), 0.0);
  Keyframe a, b;
  a.t = 0.0;
  a.position = {0.0, 0.0, 0.005};
  b.t = 0.05;
  b.position = {0.0, 0.0, -0.01};
  auto motion = std::make_shared<KeyframeMotion>(std::vector<Keyframe>{a, b});
  ContactPotential potential({0}, {}, {{plane, motion}});
  Eigen::Vector3d x = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  int rejected = 0;
  for (int step = 0; step < 10; ++step) {
    const double t0 = step * dt;
    const Eigen::Vector3d x_pred = x + dt * v;
    bool accepted = false;
    Eigen::Vector3d z = x;
    for (int attempt = 0; !accepted && attempt <= potential.max_refinements(); ++attempt) {
      const bool active = potential.begin_substep(t0, dt, rows({x}), rows({x}));
      z = x;
      auto energy = [&](const Eigen::Vector3d& y, Eigen::Vector3d* g, Eigen::Matrix3d* H) {
        Eigen::Vector3d gu = Eigen::Vector3d::Zero();
        Eigen::Matrix3d Hu = Eigen::Matrix3d::Zero();
        const double u = active ? potential.evaluate(0, y, &gu, &Hu) : 0.0;
        if (g) *g = m / (dt * dt) * (y - x_pred) + k_spring * y + gu;
        if (H) *H = (m / (dt * dt) + k_spring) * Eigen::Matrix3d::Identity() + Hu;
        return 0.5 * m / (dt * dt) * (y - x_pred).squaredNorm() + 0.5 * k_spring * y.squaredNorm() + u;
      };
      for (int it = 0; it < 50; ++it) {
        Eigen::Vector3d g;
        Eigen::Matrix3d H;
        const double e = energy(z, &g, &H);
        const Eigen::Vector3d dz = -H.ldlt().solve(g);
        if (dz.norm() < 1e-13) break;
        double alpha = 1.0;  // backtracking on Φ (u is only C¹)
        while (alpha > 1e-8 && energy(z + alpha * dz, nullptr, nullptr) > e + 1e-4 * alpha * g.dot(dz)) alpha *= 0.5;
        z += alpha * dz;
      }
      accepted = active ? potential.accept_substep(rows({z})) : true;
      if (!accepted) ++rejected;
    }
    ASSERT_TRUE(accepted);
    v = (z - x) / dt;
    x = z;
  }
  const ContactStats s = potential.stats();
  EXPECT_GE(rejected, 1);
  EXPECT_EQ(s.refinements, rejected);
  EXPECT_EQ(s.unresolved, 0);
  EXPECT_LE(potential.penetration()(0), potential.parameters().tolerance);
  const double s_end = -0.01, delta = potential.parameters().margin;
  EXPECT_LE(x.z() - s_end, potential.parameters().tolerance);  // penetration, measured directly
  const double k = potential.node_stiffness(0);
  // After 5 held steps the backward-Euler transient (factor (m/dt²)/(m/dt² + k + k_s) ≲ 1e-3 per step)
  // is gone: the analytic equilibrium to 1e-9 m.
  EXPECT_NEAR(x.z(), k * (s_end - delta) / (k + k_spring), 1e-9);
  EXPECT_NEAR(potential.contact_force()(0, 2), k_spring * x.z(), 1e-6);  // it balances the spring −k_s z
}

// A free 1 kg sphere released touching nine fixed nodes (a loose tolerance: no refinement, so the
// penalty is a fixed conservative spring): symplectic Euler with the lagged reaction keeps it
// oscillating about its rest sag without drifting away; averaged over the last half second the
// reaction is its weight.
TEST(ContactPotential, FreeObjectRestsOnNodes) {
  const Eigen::Vector3d gravity(0.0, 0.0, -9.81);
  const double mass = 1.0, radius = 0.05, dt = 1e-3;
  auto sphere = std::make_shared<Sphere>(radius);
  Pose start;
  start.translation = {0.0, 0.0, radius + 1e-3};  // the centre node at φ = δ
  auto motion = std::make_shared<FreeMotion>(mass, gravity, start, Eigen::Vector3d::Zero());
  RowMatrixX3d p(9, 3);
  for (int i = 0; i < 9; ++i) p.row(i) << 0.01 * (i % 3 - 1), 0.01 * (i / 3 - 1), 0.0;
  ContactParameters parameters;
  parameters.tolerance = 0.01;
  ContactPotential potential({0, 1, 2, 3, 4, 5, 6, 7, 8}, {}, {{sphere, motion}}, parameters);
  Eigen::Vector3d mean_force = Eigen::Vector3d::Zero();
  int samples = 0;
  double lowest = start.translation.z();
  for (int n = 0; n < 1500; ++n) {
    if (potential.begin_substep(n * dt, dt, p, p)) {
      RowMatrixX3d pc(static_cast<Eigen::Index>(potential.candidates().size()), 3);
      for (std::size_t c = 0; c < potential.candidates().size(); ++c)
        pc.row(static_cast<Eigen::Index>(c)) = p.row(potential.candidates()[c]);
      while (!potential.accept_substep(pc)) {
      }
    }
    lowest = std::min(lowest, motion->position().z());
    if (n >= 1000) {
      mean_force += potential.obstacle_force(0);
      ++samples;
    }
  }
  mean_force /= samples;
  // It oscillates on the penalty springs (symplectic Euler adds no damping), period ~0.05–0.07 s for
  // 5–9 engaged nodes of 2250 N/m: the half-second mean is the weight within ~1/(2π·7) ≈ 2 %; 10 % bound.
  EXPECT_NEAR(mean_force.z(), mass * 9.81, 0.1 * mass * 9.81);
  EXPECT_GT(lowest, radius - 0.004);
  EXPECT_EQ(potential.stats().refinements, 0);
  EXPECT_LT(motion->position().z(), radius + 1e-3);  // still in contact
}

// At a concave feature the curvature term is PSD already: the projection must leave the exact Hessian.
// (Hessians are asked for without gradients here, as an integrator may.)
// A box mesh turned inside out (the obstacle is everything outside the box) has concave edges; a node
// 0.5 mm beyond one of them is 0.5 mm deep.
TEST(ContactPotential, ProjectionKeepsTheExactHessianAtConcaveFeatures) {
  Surface s = Box(Eigen::Vector3d(0.1, 0.1, 0.1)).local_surface(4);
  s.triangles.col(1).swap(s.triangles.col(2));
  auto room = std::make_shared<TriangleMesh>(s.vertices, s.triangles);
  const Eigen::Vector3d p(0.1 + 0.0003, 0.02, 0.1 + 0.0004);  // edge region of the +x/+z edge
  ASSERT_NEAR(room->distance(p), -0.0005, 1e-15);
  ContactParameters exact;
  exact.project_hessian = false;
  ContactPotential projected({0}, {}, {{room, nullptr}}), unprojected({0}, {}, {{room, nullptr}}, exact);
  ASSERT_TRUE(projected.begin_substep(0.0, 0.01, rows({p}), rows({p})));
  ASSERT_TRUE(unprojected.begin_substep(0.0, 0.01, rows({p}), rows({p})));
  Eigen::Matrix3d H, H_exact;
  projected.evaluate(0, p, nullptr, &H);
  unprojected.evaluate(0, p, nullptr, &H_exact);
  EXPECT_LT((H - H_exact).norm(), 1e-9 * H_exact.norm()) << H << "\nexact\n" << H_exact;
  // … and the curvature part is really there: more than Gauss–Newton in the bending direction.
  const Eigen::Vector3d n = Eigen::Vector3d(0.0003, 0.0, 0.0004).normalized();
  const Eigen::Vector3d bend = Eigen::Vector3d(0.0004, 0.0, -0.0003).normalized();
  EXPECT_NEAR(n.dot(H * n), projected.node_stiffness(0), 1e-9 * H.norm());
  EXPECT_GT(bend.dot(H * bend), 0.1 * projected.node_stiffness(0));
}

TEST(ContactPotential, LumpedVertexAreasSumToTheSurfaceArea) {
  const Surface s = Box(Eigen::Vector3d(0.3, 0.2, 0.1)).local_surface(4);
  const std::vector<double> area = lumped_vertex_areas(s.vertices, s.triangles);
  double total = 0.0;
  for (double a : area) total += a;
  EXPECT_NEAR(total, 8.0 * (0.3 * 0.2 + 0.3 * 0.1 + 0.2 * 0.1), 1e-14);
}

TEST(ContactPotential, BadInputThrows) {
  auto sphere = std::make_shared<Sphere>(0.1);
  EXPECT_THROW(ContactPotential({2, 1}, {}, {{sphere, nullptr}}), Error);
  EXPECT_THROW(ContactPotential({1, 2}, {1.0}, {{sphere, nullptr}}), Error);
  EXPECT_THROW(ContactPotential({1}, {}, {{nullptr, nullptr}}), Error);
  ContactParameters bad;
  bad.tolerance = 0.0;
  EXPECT_THROW(ContactPotential({1}, {}, {{sphere, nullptr}}, bad), Error);
  ContactPotential potential({1}, {}, {{sphere, nullptr}});
  EXPECT_THROW(potential.begin_substep(0.0, 0.01, RowMatrixX3d::Zero(2, 3), RowMatrixX3d::Zero(2, 3)), Error);
  ASSERT_TRUE(potential.begin_substep(0.0, 0.01, RowMatrixX3d::Zero(1, 3), RowMatrixX3d::Zero(1, 3)));
  EXPECT_TRUE(std::isnan(potential.evaluate(0, Eigen::Vector3d::Constant(std::nan("")), nullptr, nullptr)));
}

}  // namespace
}  // namespace sflsh::scene
