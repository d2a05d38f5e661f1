// Constant nodal loads as a node potential: value, gradient and Hessian, candidates, clearing, bad input.
#include <sflsh/core/error.hpp>
#include <sflsh/scene/node_loads.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace sflsh::scene {
namespace {

TEST(NodeLoads, ValueGradientAndHessianOfAConstantForce) {
  NodeLoads loads({2, 5, 9});
  EXPECT_FALSE(loads.begin_substep(0.0, 0.01, {}, {}));  // no load: idle
  loads.add(2, Eigen::Vector3d(1.0, -2.0, 0.5));
  loads.add(0, Eigen::Vector3d(0.0, 3.0, 0.0));
  loads.add(2, Eigen::Vector3d(1.0, 0.0, 0.0));  // adds up on the same entry
  ASSERT_TRUE(loads.begin_substep(0.0, 0.01, {}, {}));
  ASSERT_EQ(loads.candidates(), (std::vector<int>{0, 2}));
  EXPECT_LT((loads.total() - Eigen::Vector3d(2.0, 1.0, 0.5)).norm(), 1e-15);
  const Eigen::Vector3d p(0.1, 0.2, -0.3);
  Eigen::Vector3d g;
  Eigen::Matrix3d H;
  const double u = loads.evaluate(1, p, &g, &H);
  EXPECT_DOUBLE_EQ(u, -Eigen::Vector3d(2.0, -2.0, 0.5).dot(p));  // u = −f·p, the work of the load
  // Central differences of a linear function are exact up to rounding (|u| ~ 1 J, h = 1e-6 m).
  for (int d = 0; d < 3; ++d) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[d] = 1e-6;
    const double fd = (loads.evaluate(1, p + e, nullptr, nullptr) - loads.evaluate(1, p - e, nullptr, nullptr)) / 2e-6;
    EXPECT_NEAR(g[d], fd, 1e-8);
  }
  EXPECT_TRUE(H.isZero(0.0));
  EXPECT_TRUE(loads.accept_substep({}));
  loads.clear();
  EXPECT_TRUE(loads.candidates().empty());
  EXPECT_TRUE(loads.total().isZero(0.0));
}

TEST(NodeLoads, BadInputIsRefused) {
  EXPECT_THROW(NodeLoads({3, 1}), Error);
  EXPECT_THROW(NodeLoads({-1, 2}), Error);
  NodeLoads loads({1, 2});
  EXPECT_THROW(loads.add(2, Eigen::Vector3d::Zero()), Error);
  EXPECT_THROW(loads.add(0, Eigen::Vector3d(std::nan(""), 0.0, 0.0)), Error);
}

}  // namespace
}  // namespace sflsh::scene
