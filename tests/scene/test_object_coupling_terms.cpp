// The energies of a free rigid object inside a body's Newton solve (object_coupling_terms.hpp) against central
// differences at a non-zero increment y (the body's solver does not re-base y), in y and, for the skin point's
// terms, in (p, y).
#include "../material/finite_difference.hpp"

#include <sflsh/scene/object_coupling_terms.hpp>

#include <gtest/gtest.h>

namespace sflsh::scene {
namespace {

using testing::central_gradient;
using testing::central_jacobian;
using testing::relative_error;

// Steps of 1e-6 (m, rad) on energies whose third derivatives are ≲ k·ℓ ~ 1e5: truncation h²/6·|f'''| ≲ 1e-8
// relative to gradients ~ 1e1–1e2, rounding ε|f|/h ~ 1e-10; 1e-5 relative leaves room for both.
constexpr double kStep = 1e-6;
constexpr double kTolerance = 1e-5;

RigidPlacement start_placement() {
  return {Eigen::Vector3d(0.1, 0.3, -0.05),
          Eigen::AngleAxisd(0.5, Eigen::Vector3d(0.2, 1.0, -0.4).normalized()).toRotationMatrix()};
}

Vector6d increment() {
  Vector6d y;
  y << 0.004, -0.006, 0.002, 0.05, -0.12, 0.08;  // a substep's worth of motion and turn
  return y;
}

TEST(ObjectCouplingTerms, InertiaAtAnIncrementMatchesFiniteDifferences) {
  const RigidProperties props = box_properties(Eigen::Vector3d(0.1, 0.05, 0.08), 800.0);
  RigidState start;
  start.placement = start_placement();
  start.velocity = Eigen::Vector3d(0.3, -1.0, 0.2);
  start.angular_velocity = Eigen::Vector3d(2.0, 0.5, -1.0);
  const double h = 1.0 / 120.0;
  const Eigen::Vector3d g(0.0, -9.81, 0.0);
  auto value = [&](const Vector6d& y) {
    return object_inertia(props, start, h, g, ObjectFrame(start.placement, y), nullptr, nullptr);
  };
  auto gradient = [&](const Vector6d& y) {
    Vector6d out = Vector6d::Zero();
    object_inertia(props, start, h, g, ObjectFrame(start.placement, y), &out, nullptr);
    return out;
  };
  const Vector6d y = increment();
  Vector6d G = Vector6d::Zero();
  Matrix6d H = Matrix6d::Zero();
  object_inertia(props, start, h, g, ObjectFrame(start.placement, y), &G, &H);
  EXPECT_LT(relative_error(central_gradient<6>(value, y, kStep), G, 1e-8), kTolerance);
  EXPECT_LT(relative_error(central_jacobian<6, 6>(gradient, y, kStep), H, 1e-8), kTolerance);
  // Without other terms the minimizer is x̃ + h² g and R̃: the gradient vanishes there.
  Vector6d free_flight;
  free_flight << h * start.velocity + h * h * g, h * start.angular_velocity;
  Vector6d at_min = Vector6d::Zero();
  object_inertia(props, start, h, g, ObjectFrame(start.placement, free_flight), &at_min, nullptr);
  EXPECT_LT(at_min.norm(), 1e-9 * G.norm() + 1e-9);
}

TEST(ObjectCouplingTerms, SampleAgainstAnObstacleMatchesFiniteDifferences) {
  Sphere obstacle(0.5);  // a curved obstacle exercises ∇²φ
  RigidSample sample{Eigen::Vector3d(0.03, -0.06, 0.02), 0.02, 5e4};
  const RigidPlacement start = start_placement();
  // Centred so that the sample's ball is 3 mm inside the obstacle at the test increment.
  const ObjectFrame at(start, increment());
  const Eigen::Vector3d w = at.R * sample.point + at.x;
  Pose pose;
  pose.translation = w - (0.5 + sample.radius - 0.003) * Eigen::Vector3d(0.3, -1.0, 0.2).normalized();
  obstacle.set_pose(pose);
  auto value = [&](const Vector6d& y) {
    return sample_penalty(obstacle, sample, 1e-3, ObjectFrame(start, y), nullptr, nullptr);
  };
  auto gradient = [&](const Vector6d& y) {
    Vector6d out = Vector6d::Zero();
    sample_penalty(obstacle, sample, 1e-3, ObjectFrame(start, y), &out, nullptr);
    return out;
  };
  const Vector6d y = increment();
  Vector6d G = Vector6d::Zero();
  Matrix6d H = Matrix6d::Zero();
  ASSERT_GT(sample_penalty(obstacle, sample, 1e-3, ObjectFrame(start, y), &G, &H), 0.0) << "must touch";
  EXPECT_LT(relative_error(central_gradient<6>(value, y, kStep), G, 1e-8), kTolerance);
  EXPECT_LT(relative_error(central_jacobian<6, 6>(gradient, y, kStep), H, 1e-8), kTolerance);
}

/// v = (p, y) → the term's value, gradient (9) and exact Hessian (not projected).
template <typename Term>
void expect_point_term(const Term& term, const Vector9d& v0, const char* what) {
  auto value = [&](const Vector9d& v) { return term(v, nullptr, nullptr); };
  auto gradient = [&](const Vector9d& v) {
    Vector9d out = Vector9d::Zero();
    term(v, &out, nullptr);
    return out;
  };
  Vector9d G = Vector9d::Zero();
  Matrix9d H = Matrix9d::Zero();
  ASSERT_GT(term(v0, &G, &H), 0.0) << what << ": must be active";
  EXPECT_LT(relative_error(central_gradient<9>(value, v0, kStep), G, 1e-8), kTolerance) << what;
  EXPECT_LT(relative_error(central_jacobian<9, 9>(gradient, v0, kStep), H, 1e-8), kTolerance) << what << "\n" << H;
}

TEST(ObjectCouplingTerms, SkinPointAgainstTheObjectMatchesFiniteDifferences) {
  const RigidPlacement start = start_placement();
  const Sphere ball(0.06);
  const Box box(Eigen::Vector3d(0.1, 0.05, 0.08));
  const Vector6d y = increment();
  const ObjectFrame frame(start, y);
  for (const auto& [shape, name] : {std::pair<const Obstacle*, const char*>{&ball, "sphere"}, {&box, "box"}}) {
    // A skin point 4 mm inside the shape, off its symmetry planes.
    const Eigen::Vector3d local =
        shape == &ball ? Eigen::Vector3d(0.02, 0.035, -0.03).normalized() * 0.056 : Eigen::Vector3d(0.04, 0.046, -0.02);
    Vector9d v0;
    v0 << frame.R * local + frame.x, y;
    auto term = [&, s = shape](const Vector9d& v, Vector9d* g, Matrix9d* H) {
      return point_penalty(*s, v.head<3>(), 2e3, 1e-3, ObjectFrame(start, v.tail<6>()), g, H, false);
    };
    expect_point_term(term, v0, name);
  }
}

TEST(ObjectCouplingTerms, FrictionWithTheSkinMatchesFiniteDifferences) {
  const RigidPlacement start = start_placement();
  FrictionContact c;
  c.point = Eigen::Vector3d(0.01, 0.05, -0.03);
  c.normal = Eigen::Vector3d(0.3, 0.9, -0.1).normalized();
  c.normal_force = 20.0;
  const Eigen::Vector3d p_start(0.2, 0.1, 0.0);
  for (const double epsilon : {1e-1, 1e-5}) {  // sticking (inside the smoothing) and sliding
    const Vector6d y = increment();
    Vector9d v0;
    v0 << p_start + Eigen::Vector3d(0.001, -0.002, 0.0005), y;
    auto term = [&](const Vector9d& v, Vector9d* g, Matrix9d* H) {
      return point_friction(c, v.head<3>(), p_start, 0.5, epsilon, ObjectFrame(start, v.tail<6>()), g, H, false);
    };
    expect_point_term(term, v0, epsilon > 1e-3 ? "sticking" : "sliding");
  }
}

TEST(ObjectCouplingTerms, ProjectedHessiansArePositiveSemiDefinite) {
  const RigidPlacement start = start_placement();
  const Sphere ball(0.06);
  const ObjectFrame frame(start, increment());
  const Eigen::Vector3d p = frame.R * Eigen::Vector3d(0.0, 0.05, 0.0) + frame.x;
  Matrix9d H = Matrix9d::Zero();
  point_penalty(ball, p, 2e3, 1e-3, frame, nullptr, &H, true);
  EXPECT_GT(H.norm(), 0.0);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Matrix9d>(H).eigenvalues().minCoeff(), -1e-9 * H.norm());
}

}  // namespace
}  // namespace sflsh::scene
