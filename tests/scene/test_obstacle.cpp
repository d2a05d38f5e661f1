// Signed distances of the obstacle shapes: derivatives by finite differences in each geometric regime,
// signs, surfaces, the mesh obstacle against the analytic shapes, vertex updates and mesh files.
#include "scene_test_support.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/scene/obstacle.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <numbers>
#include <random>
#include <thread>

namespace sflsh::scene {
namespace {

using testing::central_gradient;
using testing::central_jacobian;
using testing::relative_error;

Pose tilted_obstacle_pose() {
  Pose pose;
  pose.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  pose.translation = Eigen::Vector3d(0.3, -0.2, 0.1);
  return pose;
}

/// Checks ∇φ and ∇²φ of `shape` at the local points (mapped to the world by its pose) by central
/// differences. Points are chosen ≥ 0.05 m from every set where φ is not C² (see obstacle.hpp), so the
/// error bound of scene_test_support.hpp holds: 1e-6 leaves two orders of margin.
void expect_derivatives(const Obstacle& shape, const std::vector<Eigen::Vector3d>& local_points) {
  for (const Eigen::Vector3d& q : local_points) {
    const Eigen::Vector3d p = shape.pose().to_world(q);
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    shape.distance(p, &g, &H);
    const Eigen::Vector3d g_fd = central_gradient([&](const Eigen::Vector3d& x) { return shape.distance(x); }, p);
    const Eigen::Matrix3d H_fd = central_jacobian(
        [&](const Eigen::Vector3d& x) {
          Eigen::Vector3d gx;
          shape.distance(x, &gx);
          return gx;
        },
        p);
    EXPECT_LT(relative_error(g, g_fd, 1.0), 1e-6) << "gradient at local " << q.transpose();
    EXPECT_LT(relative_error(H, H_fd, 1.0), 1e-6) << "Hessian at local " << q.transpose() << "\n"
                                                  << H << "\nfd\n"
                                                  << H_fd;
    EXPECT_NEAR(g.norm(), 1.0, 1e-12);                   // a distance has |∇φ| = 1
    EXPECT_LT((H * g).norm(), 1e-9 * (1.0 + H.norm()));  // and ∇²φ ∇φ = 0
    EXPECT_LT((H - H.transpose()).norm(), 1e-12);
  }
}

TEST(ObstacleDerivatives, HalfSpace) {
  HalfSpace plane(Eigen::Vector3d(0.0, 0.0, 2.0), 0.1);
  plane.set_pose(tilted_obstacle_pose());
  expect_derivatives(plane, {{0.2, 0.3, 0.5}, {-1.0, 0.4, -0.3}});
  EXPECT_NEAR(plane.distance(plane.pose().to_world({0.4, -0.7, 0.35})), 0.25, 1e-14);
}

TEST(ObstacleDerivatives, Sphere) {
  Sphere sphere(0.2);
  sphere.set_pose(tilted_obstacle_pose());
  expect_derivatives(sphere, {{0.3, 0.1, -0.2}, {0.05, -0.08, 0.06}, {0.0, 0.0, 0.15}});
  EXPECT_NEAR(sphere.distance(sphere.pose().to_world({0.0, 0.3, 0.4})), 0.3, 1e-14);
  EXPECT_NEAR(sphere.distance(sphere.pose().translation), -0.2, 1e-14);
}

TEST(ObstacleDerivatives, BoxInEveryRegion) {
  Box box(Eigen::Vector3d(0.3, 0.2, 0.1));
  box.set_pose(tilted_obstacle_pose());
  expect_derivatives(box, {
                              {0.1, 0.05, 0.4},    // face region (+z)
                              {0.5, 0.05, -0.3},   // edge region (x, z outside)
                              {-0.45, 0.35, 0.3},  // corner region
                              {0.1, 0.02, 0.03},   // inside, nearest face +z
                              {-0.25, 0.0, 0.0},   // inside, nearest face −x
                          });
  EXPECT_NEAR(box.distance(box.pose().to_world({0.0, 0.0, 0.0})), -0.1, 1e-14);
  EXPECT_NEAR(box.distance(box.pose().to_world({0.6, 0.6, 0.1})), 0.5, 1e-14);
}

TEST(ObstacleDerivatives, CapsuleSideCapsAndInside) {
  Capsule capsule(0.1, 0.25);
  capsule.set_pose(tilted_obstacle_pose());
  expect_derivatives(capsule, {
                                  {0.2, 0.1, 0.1},    // beside the segment
                                  {0.1, -0.1, 0.45},  // beyond +z end
                                  {0.0, 0.05, -0.4},  // beyond −z end
                                  {0.06, 0.0, 0.0},   // inside, beside the segment
                              });
  EXPECT_NEAR(capsule.distance(capsule.pose().to_world({0.0, 0.3, 0.1})), 0.2, 1e-14);
  EXPECT_NEAR(capsule.distance(capsule.pose().to_world({0.0, 0.0, 0.55})), 0.2, 1e-14);
}

// A cube as a triangle mesh: its closest point and pseudonormals must give exactly the box distance in
// face, edge and corner regions and inside, and the mesh derivatives must pass the same check.
TEST(ObstacleDerivatives, TriangleMeshMatchesBoxInEveryRegion) {
  const Box box(Eigen::Vector3d(0.3, 0.2, 0.1));
  const Surface s = box.local_surface(4);
  TriangleMesh mesh(s.vertices, s.triangles);
  EXPECT_TRUE(mesh.closed());
  const std::vector<Eigen::Vector3d> points = {{0.1, 0.05, 0.4},  {0.5, 0.05, -0.3}, {-0.45, 0.35, 0.3},
                                               {0.1, 0.02, 0.03}, {-0.25, 0.0, 0.0}, {0.25, -0.15, 0.06}};
  for (const auto& q : points) EXPECT_NEAR(mesh.distance(q), box.distance(q), 1e-12) << q.transpose();
  mesh.set_pose(tilted_obstacle_pose());
  expect_derivatives(mesh, points);
}

TEST(ObstacleSurface, ShapesGiveClosedOutwardSurfacesOnTheirZeroSet) {
  const Pose pose = tilted_obstacle_pose();
  std::vector<std::unique_ptr<Obstacle>> shapes;
  shapes.push_back(std::make_unique<Sphere>(0.2));
  shapes.push_back(std::make_unique<Box>(Eigen::Vector3d(0.3, 0.2, 0.1)));
  shapes.push_back(std::make_unique<Capsule>(0.1, 0.25));
  shapes.push_back(std::make_unique<Capsule>(0.1, 0.0));
  for (auto& shape : shapes) {
    shape->set_pose(pose);
    const Surface s = shape->surface(16);
    const TriangleMesh mesh(s.vertices, s.triangles);
    EXPECT_TRUE(mesh.closed());
    double volume = 0.0;
    for (Eigen::Index f = 0; f < s.triangles.rows(); ++f) {
      const Eigen::Vector3d a = s.vertices.row(s.triangles(f, 0)), b = s.vertices.row(s.triangles(f, 1)),
                            c = s.vertices.row(s.triangles(f, 2));
      volume += a.dot(b.cross(c)) / 6.0;
    }
    EXPECT_GT(volume, 0.0);  // outward orientation
    for (Eigen::Index v = 0; v < s.vertices.rows(); ++v) EXPECT_NEAR(shape->distance(s.vertices.row(v)), 0.0, 1e-12);
    // The world box holds the surface.
    const Aabb box = shape->bounds();
    for (Eigen::Index v = 0; v < s.vertices.rows(); ++v) EXPECT_EQ(box.distance(s.vertices.row(v).transpose()), 0.0);
  }
  HalfSpace plane(Eigen::Vector3d::UnitY(), 0.5, 2.0);
  const Surface ps = plane.surface();
  EXPECT_EQ(ps.triangles.rows(), 2);
  const Eigen::Vector3d n = (ps.vertices.row(1) - ps.vertices.row(0)).cross(ps.vertices.row(2) - ps.vertices.row(0));
  EXPECT_GT(n.dot(Eigen::Vector3d::UnitY()), 0.0);
}

TEST(ObstacleSign, InsideNegativeOutsidePositiveForEveryShape) {
  const Surface sphere_surface = Sphere(0.2).local_surface(24);
  std::vector<std::unique_ptr<Obstacle>> shapes;
  shapes.push_back(std::make_unique<Sphere>(0.2));
  shapes.push_back(std::make_unique<Box>(Eigen::Vector3d(0.2, 0.2, 0.2)));
  shapes.push_back(std::make_unique<Capsule>(0.2, 0.1));
  shapes.push_back(std::make_unique<HalfSpace>(Eigen::Vector3d::UnitX(), 0.0));
  shapes.push_back(std::make_unique<TriangleMesh>(sphere_surface.vertices, sphere_surface.triangles));
  const Pose pose = tilted_obstacle_pose();
  for (auto& shape : shapes) {
    shape->set_pose(pose);
    EXPECT_LT(shape->distance(pose.to_world({-0.05, 0.03, 0.02})), 0.0);
    EXPECT_GT(shape->distance(pose.to_world({0.6, 0.5, -0.4})), 0.0);
  }
}

// UV sphere inscribed in the analytic one: its faces lie within the sagitta r(1 − cos(π/m)) (m the
// latitude steps; the longitude chords are shorter) of the sphere, which bounds |φ_mesh − φ_sphere|.
TEST(ObstacleMesh, TriangulatedSphereAgreesWithTheAnalyticSphere) {
  const double radius = 0.1;
  const int segments = 64;
  const Sphere sphere(radius);
  const Surface s = sphere.local_surface(segments);
  const TriangleMesh mesh(s.vertices, s.triangles);
  ASSERT_TRUE(mesh.closed());
  const double sagitta = radius * (1.0 - std::cos(std::numbers::pi / (segments / 2)));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), depth(-0.05, 0.05);
  double worst = 0.0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d dir = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const Eigen::Vector3d q = (radius + depth(rng)) * dir;
    const double phi = mesh.distance(q);
    worst = std::max(worst, std::abs(phi - sphere.distance(q)));
    if (std::abs(sphere.distance(q)) > sagitta) {
      EXPECT_EQ(phi < 0.0, sphere.distance(q) < 0.0) << q.transpose();
    }
  }
  EXPECT_LE(worst, sagitta * (1.0 + 1e-9));
  EXPECT_GT(worst, 0.1 * sagitta);  // the test sees the discretisation at all
}

TEST(ObstacleMesh, UpdatingVerticesMovesTheDistance) {
  const Surface s = Sphere(0.1).local_surface(32);
  TriangleMesh mesh(s.vertices, s.triangles);
  const Eigen::Vector3d q(0.0, 0.0, 0.3);  // above the north pole (a vertex): exact distance 0.2
  EXPECT_NEAR(mesh.distance(q), 0.2, 1e-12);
  RowMatrixX3d moved = s.vertices;
  moved.col(2).array() += 0.05;  // lift the whole surface by 5 cm
  mesh.set_vertices(moved);
  EXPECT_NEAR(mesh.distance(q), 0.15, 1e-12);
  EXPECT_NEAR(mesh.local_bounds().upper.z(), 0.15, 1e-12);
  EXPECT_LT(mesh.distance({0.0, 0.0, 0.12}), 0.0);  // inside only after the move
  EXPECT_THROW(mesh.set_vertices(moved.topRows(10)), Error);
}

// The cost of following another body's posed skin: a ~14k-triangle surface refitted per step.
TEST(ObstacleMesh, RebuildCostOfASkinSizedMesh) {
  const Surface s = Sphere(0.3).local_surface(120);  // 14160 triangles, 7082 vertices
  ASSERT_EQ(s.triangles.rows(), 14160);
  TriangleMesh mesh(s.vertices, s.triangles);
  RowMatrixX3d moved = s.vertices;
  const int repeats = 5;
  const auto t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < repeats; ++r) {
    moved.col(0).array() += 0.001;
    mesh.set_vertices(moved);
  }
  const double rebuild = sflsh::seconds_since(t0) / repeats;
  // Queries where contact candidates are: within 2 cm of the surface.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), depth(-0.02, 0.02);
  const int queries = 10000;
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < queries; ++i)
    points.push_back((0.3 + depth(rng)) * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized());
  double sum = 0.0;
  const auto t1 = std::chrono::steady_clock::now();
  for (const auto& q : points) {
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    sum += mesh.distance(q, &g, &H);
  }
  const double query = sflsh::seconds_since(t1) / queries;
  std::cout << "[ measure  ] 14160-triangle mesh: set_vertices " << 1e3 * rebuild << " ms, distance query "
            << 1e6 * query << " us (checksum " << sum << ")\n";
  RecordProperty("rebuild_ms", std::to_string(1e3 * rebuild));
  RecordProperty("query_us", std::to_string(1e6 * query));
  EXPECT_LT(rebuild, 0.5);  // generous: a refit must stay far below a frame's budget even on a busy CI
}

// Integrators evaluate the potential from several threads: concurrent queries give the serial answers.
TEST(ObstacleMesh, ConcurrentQueriesAgreeWithSerialOnes) {
  const Surface s = Sphere(0.1).local_surface(48);
  const TriangleMesh mesh(s.vertices, s.triangles);
  std::vector<Eigen::Vector3d> points;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-0.12, 0.12);
  for (int i = 0; i < 2000; ++i) points.emplace_back(unit(rng), unit(rng), unit(rng));
  std::vector<double> serial(points.size()), parallel(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) serial[i] = mesh.distance(points[i]);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t i = static_cast<std::size_t>(t); i < points.size(); i += 4)
        parallel[i] = mesh.distance(points[i]);
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(serial, parallel);
}

TEST(ObstacleMesh, LoadsObjStlAndPlyFiles) {
  const auto dir = testing::scratch_dir();
  {  // a 2 × 1 × 1 box with quads (1-based indices), in mm
    std::ofstream obj(dir / "box.obj");
    obj << "# box\nv 0 0 0\nv 2000 0 0\nv 2000 1000 0\nv 0 1000 0\nv 0 0 1000\nv 2000 0 1000\nv 2000 1000 1000\nv 0 "
           "1000 1000\n"
           "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
  }
  const auto box = TriangleMesh::load(dir / "box.obj", 0.001);
  EXPECT_EQ(box->triangles().rows(), 12);
  EXPECT_EQ(box->vertices().rows(), 8);
  EXPECT_TRUE(box->closed());
  EXPECT_NEAR(box->distance({1.0, 0.5, 0.5}), -0.5, 1e-12);
  EXPECT_NEAR(box->distance({1.0, 0.5, 1.5}), 0.5, 1e-12);
  {  // a tetrahedron in ASCII STL, every facet with its own copies of the corners, stored inward
    const Eigen::Vector3d x[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const int faces[4][3] = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};  // inward (negative volume)
    std::ofstream stl(dir / "tet.stl");
    stl << "solid tet\n";
    for (const auto& f : faces) {
      stl << " facet normal 0 0 0\n  outer loop\n";
      for (int k : f) stl << "   vertex " << x[k].x() << " " << x[k].y() << " " << x[k].z() << "\n";
      stl << "  endloop\n endfacet\n";
    }
    stl << "endsolid tet\n";
  }
  const auto tet = TriangleMesh::load(dir / "tet.stl");
  EXPECT_EQ(tet->vertices().rows(), 4);  // merged
  EXPECT_TRUE(tet->closed());
  EXPECT_LT(tet->distance({0.1, 0.1, 0.1}), 0.0);  // flipped outward on load
  EXPECT_GT(tet->distance({1.0, 1.0, 1.0}), 0.0);
  {
    std::ofstream ply(dir / "tet.ply");
    ply << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  }
  const auto ply = TriangleMesh::load(dir / "tet.ply");
  EXPECT_TRUE(ply->closed());
  EXPECT_NEAR(ply->distance({0.1, 0.1, -0.2}), 0.2, 1e-7);  // below the z = 0 face (float file)
  EXPECT_THROW(TriangleMesh::load(dir / "missing.obj"), Error);
  EXPECT_THROW(TriangleMesh::load(dir / "box.off"), Error);
}

TEST(ObstacleInput, BadShapesThrow) {
  EXPECT_THROW(Sphere(-1.0), Error);
  EXPECT_THROW(Box(Eigen::Vector3d(1.0, 0.0, 1.0)), Error);
  EXPECT_THROW(Capsule(0.1, -0.1), Error);
  EXPECT_THROW(HalfSpace(Eigen::Vector3d::Zero(), 0.0), Error);
  RowMatrixX3d v(3, 3);
  v << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  RowMatrixX3i f(1, 3);
  f << 0, 1, 3;
  EXPECT_THROW(TriangleMesh(v, f), Error);
  f << 0, 1, 2;
  EXPECT_FALSE(TriangleMesh(v, f).closed());
}

}  // namespace
}  // namespace sflsh::scene
