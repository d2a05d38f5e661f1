// check_surface on small meshes built here: closed solids pass, broken ones report what is broken.
#include <sflsh/body/surface_checks.hpp>
#include <sflsh/core/error.hpp>

#include <gmock/gmock.h>

using namespace sflsh::body;

namespace {

struct Mesh {
  RowMatrixX3d v;
  RowMatrixX3i f;
};

Mesh tetrahedron() {
  Mesh m;
  m.v.resize(4, 3);
  m.v << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.f.resize(4, 3);
  m.f << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return m;
}

/// The octahedron |x| + |y| + |z| ≤ 1 scaled by `r` and moved by `shift`, faces outward.
Mesh octahedron(double r = 1.0, const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  Mesh m;
  m.v.resize(6, 3);
  m.v << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  m.v = (r * m.v).rowwise() + shift.transpose();
  m.f.resize(8, 3);
  int row = 0;
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) {
        const int a = sx > 0 ? 0 : 1, b = sy > 0 ? 2 : 3, c = sz > 0 ? 4 : 5;
        if (sx * sy * sz > 0)
          m.f.row(row++) << a, b, c;
        else
          m.f.row(row++) << a, c, b;
      }
  return m;
}

Mesh merged(const Mesh& a, const Mesh& b) {
  Mesh m;
  m.v.resize(a.v.rows() + b.v.rows(), 3);
  m.v << a.v, b.v;
  m.f.resize(a.f.rows() + b.f.rows(), 3);
  m.f << a.f, (b.f.array() + static_cast<int>(a.v.rows())).matrix();
  return m;
}

}  // namespace

TEST(SurfaceChecks, TetrahedronIsAClosedOutwardSolid) {
  const Mesh m = tetrahedron();
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.connected_components, 1);
  EXPECT_EQ(r.self_intersections, 0);
  EXPECT_NEAR(r.volume, 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(r.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-12);
  EXPECT_NEAR(r.min_angle_deg, 45.0, 1e-9);
}

TEST(SurfaceChecks, OctahedronIsAClosedOutwardSolid) {
  const Mesh m = octahedron();
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_NEAR(r.volume, 4.0 / 3.0, 1e-12);
  EXPECT_NEAR(r.min_angle_deg, 60.0, 1e-9);
  EXPECT_THAT(r.summary(), ::testing::HasSubstr("closed, manifold, oriented outward, 1 component"));
}

TEST(SurfaceChecks, RemovedFaceIsNotClosed) {
  Mesh m = octahedron();
  m.f = m.f.topRows(7).eval();
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_FALSE(r.closed);
  EXPECT_TRUE(r.edge_manifold);
  EXPECT_TRUE(r.vertex_manifold);  // boundary fans are disks
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_FALSE(r.ok());
  EXPECT_THAT(r.summary(), ::testing::HasSubstr("NOT closed"));
}

TEST(SurfaceChecks, FlippedFaceIsNotConsistentlyOriented) {
  Mesh m = octahedron();
  std::swap(m.f(3, 1), m.f(3, 2));
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_TRUE(r.closed);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_FALSE(r.outward);
  EXPECT_FALSE(r.ok());
}

TEST(SurfaceChecks, InsideOutSolidIsNotOutward) {
  Mesh m = octahedron();
  m.f.col(1).swap(m.f.col(2));
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_FALSE(r.outward);
  EXPECT_NEAR(r.volume, -4.0 / 3.0, 1e-12);
  EXPECT_FALSE(r.ok());
}

TEST(SurfaceChecks, InterpenetratingOctahedraSelfIntersect) {
  const Mesh m = merged(octahedron(), octahedron(1.0, Eigen::Vector3d(0.5, 0.3, 0.2)));
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_GT(r.self_intersections, 0);
  EXPECT_EQ(r.connected_components, 2);
  EXPECT_FALSE(r.ok());
}

TEST(SurfaceChecks, SeparateOctahedraAreTwoComponents) {
  const Mesh m = merged(octahedron(), octahedron(1.0, Eigen::Vector3d(3.0, 0.0, 0.0)));
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_EQ(r.connected_components, 2);
  EXPECT_EQ(r.self_intersections, 0);
  EXPECT_EQ(r.euler_characteristic, 4);
  EXPECT_TRUE(r.closed);
  EXPECT_FALSE(r.ok());
}

TEST(SurfaceChecks, NestedOctahedraDoNotIntersect) {
  // One inside the other: two components, no face crossing.
  const Mesh m = merged(octahedron(), octahedron(0.3));
  EXPECT_EQ(check_surface(m.v, m.f).self_intersections, 0);
}

TEST(SurfaceChecks, FoldedFacesSharingAnEdgeIntersect) {
  // Two coplanar triangles on the same side of their shared edge overlap.
  RowMatrixX3d v(4, 3);
  v << 0, 0, 0, 1, 0, 0, 0.2, 1, 0, 0.8, 0.5, 0;
  RowMatrixX3i f(2, 3);
  f << 0, 1, 2, 1, 0, 3;
  EXPECT_EQ(check_surface(v, f).self_intersections, 1);
  // Hinged the other way they only share the edge.
  v(3, 1) = -0.5;
  EXPECT_EQ(check_surface(v, f).self_intersections, 0);
}

TEST(SurfaceChecks, FacesSharingAVertexCanCross) {
  // A triangle piercing another one that it touches at a common vertex.
  RowMatrixX3d v(5, 3);
  v << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.3, -0.5, 0.3, 0.3, 0.5;
  RowMatrixX3i f(2, 3);
  f << 0, 1, 2, 0, 3, 4;
  EXPECT_EQ(check_surface(v, f).self_intersections, 1);
}

TEST(SurfaceChecks, NonManifoldEdgeAndVertex) {
  // Three triangles on one edge.
  RowMatrixX3d v(5, 3);
  v << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0.5, 0, 0, 1;
  RowMatrixX3i f(3, 3);
  f << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  const SurfaceReport edge = check_surface(v, f);
  EXPECT_FALSE(edge.edge_manifold);
  EXPECT_FALSE(edge.vertex_manifold);

  // Two tetrahedra touching at one vertex (a bow tie): edges fine, the shared vertex is not.
  Mesh a = tetrahedron();
  Mesh b = tetrahedron();
  b.v = (-b.v).eval();
  b.f.col(1).swap(b.f.col(2));
  Mesh m = merged(a, b);
  // Weld b's apex (vertex 4, at the origin) onto a's vertex 0.
  for (Eigen::Index t = 0; t < m.f.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      if (m.f(t, k) == 4) m.f(t, k) = 0;
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.edge_manifold);
  EXPECT_FALSE(r.vertex_manifold);
  EXPECT_EQ(r.connected_components, 1);
  EXPECT_FALSE(r.ok());
}

TEST(SurfaceChecks, DegenerateFaceIsCounted) {
  Mesh m = octahedron();
  m.v.row(4) = Eigen::RowVector3d(0.5, 0.5, 0.0);  // top vertex onto the edge between +x and +y
  const SurfaceReport r = check_surface(m.v, m.f);
  EXPECT_GE(r.degenerate_faces, 1);
  EXPECT_FALSE(r.ok());
}

TEST(SurfaceChecks, IntersectionTestIsOptionalAndIndicesAreChecked) {
  const Mesh m = octahedron();
  EXPECT_EQ(check_surface(m.v, m.f, false).self_intersections, -1);
  RowMatrixX3i bad = m.f;
  bad(2, 1) = 17;
  EXPECT_THAT([&] { check_surface(m.v, bad); },
              ::testing::ThrowsMessage<sflsh::Error>(::testing::HasSubstr("face 2 references vertex 17")));
}
