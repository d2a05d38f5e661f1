// Surface operators and the bounded biharmonic basis of the material control points: operator identities,
// interpolation, bounds, partition of unity, optimality (KKT, and energy against feasible alternatives),
// locality, determinism, errors, and the .npz cache.
#include "error_of.hpp"
#include "scratch_dir.hpp"
#include "test_fields_meshes.hpp"

#include <sflsh/core/npz.hpp>
#include <sflsh/material/biharmonic_basis.hpp>
#include <sflsh/material/control_points.hpp>
#include <sflsh/material/surface_operators.hpp>

#include <Eigen/Dense>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

namespace sflsh {

using namespace sflsh::material;
using sflsh::testing::error_of;
using sflsh::testing::FieldMesh;
using ::testing::HasSubstr;

namespace {

// Σ_faces area·|∇u|², the Dirichlet energy of the piecewise-linear u written independently of the cotangent
// formula: ∇u on a triangle from the 2×2 metric of its edges.
double dirichlet_energy(const RowMatrixX3d& V, const RowMatrixX3i& F, const Eigen::VectorXd& u) {
  double energy = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d e1 = (V.row(F(f, 1)) - V.row(F(f, 0))).transpose();
    const Eigen::Vector3d e2 = (V.row(F(f, 2)) - V.row(F(f, 0))).transpose();
    Eigen::Matrix2d G;
    G << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const Eigen::Vector2d du(u(F(f, 1)) - u(F(f, 0)), u(F(f, 2)) - u(F(f, 0)));
    energy += 0.5 * e1.cross(e2).norm() * du.dot(G.inverse() * du);  // area · duᵀ G⁻¹ du = area·|∇u|²
  }
  return energy;
}

std::vector<int> controls(const FieldMesh& m, int count) { return place_control_points(m.V, m.F, count); }

// Worst KKT violation of φ as the minimizer of ½φᵀQφ with φ(s_i) = δ and 0 ≤ φ ≤ 1, relative to max diag(Q):
// the gradient g = Qφ must vanish where 0 < φ < 1, be ≥ 0 where φ = 0 and ≤ 0 where φ = 1.
double kkt_violation(const SparseMatrixd& Q, const Eigen::VectorXd& phi, const std::vector<int>& known) {
  const Eigen::VectorXd g = Q * phi;
  std::vector<char> fixed(static_cast<std::size_t>(phi.size()), 0);
  for (const int k : known) fixed[static_cast<std::size_t>(k)] = 1;
  double worst = 0.0;
  for (Eigen::Index j = 0; j < phi.size(); ++j) {
    if (fixed[static_cast<std::size_t>(j)]) continue;
    const double v = phi(j) <= 0.0 ? -g(j) : (phi(j) >= 1.0 ? g(j) : std::abs(g(j)));
    worst = std::max(worst, v);
  }
  return worst / Q.diagonal().maxCoeff();
}

}  // namespace

TEST(FieldSurfaceOperators, CotangentLaplacianIsTheDirichletEnergy) {
  const FieldMesh m = sflsh::testing::icosphere(3, /*blob=*/true);
  const SparseMatrixd L = cotangent_laplacian(m.V, m.F);
  // Symmetric by construction (the same weight goes to (i, j) and (j, i)): exact.
  EXPECT_EQ((SparseMatrixd(L.transpose()) - L).norm(), 0.0);
  // L·1 = 0: each weight is added to a diagonal and subtracted off it, so rows cancel to round-off,
  // ~(row length)·eps·max|L_ij| ≈ 1e-15 relative; 1e-12 leaves room.
  const double scale = L.diagonal().maxCoeff();
  EXPECT_LT((L * Eigen::VectorXd::Ones(m.V.rows())).cwiseAbs().maxCoeff(), 1e-12 * scale);
  // uᵀLu = ∫|∇u|² (PSD convention) for random fields, against the independent per-triangle formula;
  // both are sums of ~10⁴ O(1) terms, so 1e-10 relative bounds their round-off.
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd u(m.V.rows());
    for (Eigen::Index i = 0; i < u.size(); ++i) u(i) = normal(rng);
    const double expected = dirichlet_energy(m.V, m.F, u);
    EXPECT_GT(u.dot(L * u), 0.0);
    EXPECT_NEAR(u.dot(L * u), expected, 1e-10 * expected);
  }
}

TEST(FieldSurfaceOperators, LaplacianOfLinearFunctionVanishesInsidePlanarPatch) {
  // Linear precision of the cotangent Laplacian on planar meshes: (L u)_i = 0 at interior vertices for
  // u = a·x + b·y (Pinkall & Polthier 1993); boundary vertices carry the flux, so they are excluded.
  FieldMesh m = sflsh::testing::grid_patch(12, 8);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);  // < ¼ of the 1/8 spacing: no fold-overs
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V(i, 0) += jitter(rng), m.V(i, 1) += jitter(rng);
  const Eigen::VectorXd u = 0.7 * m.V.col(0) - 1.3 * m.V.col(1);
  const Eigen::VectorXd Lu = cotangent_laplacian(m.V, m.F) * u;
  for (int i = 1; i < 12; ++i)
    for (int j = 1; j < 8; ++j) EXPECT_NEAR(Lu(i * 9 + j), 0.0, 1e-12) << "interior vertex " << i * 9 + j;
  EXPECT_GT(Lu.cwiseAbs().maxCoeff(), 0.1);  // and the boundary flux is not zero (the check can fail)
}

TEST(FieldSurfaceOperators, LumpedMassesArePositiveAndSumToTheArea) {
  const FieldMesh m = sflsh::testing::icosphere(4);
  double area = 0.0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    area += 0.5 * (m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0))).norm();
  for (const MassLumping lumping : {MassLumping::kVoronoi, MassLumping::kBarycentric}) {
    const Eigen::VectorXd mass = lumped_mass(m.V, m.F, lumping);
    EXPECT_GT(mass.minCoeff(), 0.0);
    EXPECT_NEAR(mass.sum(), area, 1e-12 * area);  // both split each triangle's area exactly
  }
  EXPECT_NEAR(area, 4.0 * M_PI, 0.01 * 4.0 * M_PI);  // the level-4 icosphere is within 1% of the sphere
}

TEST(FieldSurfaceOperators, DijkstraDistancesOnTheGrid) {
  const FieldMesh m = sflsh::testing::grid_patch(10, 10);  // spacing 0.2 in x, 0.1 in y
  const VertexAdjacency adjacency = vertex_adjacency(m.F, static_cast<int>(m.V.rows()));
  EXPECT_EQ(adjacency.of(0).size(), 3u);  // a left corner: right, up and the a–c diagonal
  const std::vector<int> source = {0};
  const Eigen::VectorXd d = edge_distances(m.V, adjacency, source);
  // From the corner (−1, 0) along the bottom edge to (1, 0): 10 edges of 0.2, exactly 2 up to round-off.
  EXPECT_NEAR(d(10 * 11), 2.0, 1e-12);
  for (Eigen::Index v = 0; v < m.V.rows(); ++v)  // never shorter than the straight line
    EXPECT_GE(d(v), (m.V.row(v) - m.V.row(0)).norm() - 1e-12);
  // A uniform scale of 2 doubles every distance; the incremental update equals the two-source run.
  EXPECT_NEAR(edge_distances(m.V, adjacency, source, Eigen::VectorXd::Constant(m.V.rows(), 2.0))(110), 4.0, 1e-12);
  Eigen::VectorXd relaxed = d;
  relax_edge_distances(m.V, adjacency, 60, Eigen::VectorXd(), relaxed);
  const std::vector<int> both = {0, 60};
  EXPECT_EQ((relaxed - edge_distances(m.V, adjacency, both)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(FieldSurfaceOperators, InvalidSurfacesGiveClearErrors) {
  FieldMesh m = sflsh::testing::grid_patch(4, 2);
  RowMatrixX3i F = m.F;
  F(3, 1) = 999;
  EXPECT_THAT(error_of([&] { cotangent_laplacian(m.V, F); }), HasSubstr("face 3 has vertex index 999"));
  F = m.F;
  F(2, 2) = F(2, 0);
  EXPECT_THAT(error_of([&] { lumped_mass(m.V, F); }), HasSubstr("face 2 repeats a vertex"));
  RowMatrixX3d V = m.V;
  V(0, 1) = std::nan("");
  EXPECT_THAT(error_of([&] { validate_surface(V, m.F); }), HasSubstr("vertex 0 has a non-finite position"));
  V = m.V;
  V.conservativeResize(V.rows() + 1, 3);
  V.row(V.rows() - 1) << 5, 5, 5;
  EXPECT_THAT(error_of([&] { validate_surface(V, m.F); }), HasSubstr("not referenced by any face"));
}

TEST(BiharmonicBasis, InterpolatesIsBoundedAndSumsToOne) {
  for (const auto& [name, mesh, count] : {std::tuple{"patch", sflsh::testing::grid_patch(), 12},
                                          std::tuple{"blob", sflsh::testing::icosphere(3, true), 24},
                                          std::tuple{"body region", sflsh::testing::body_region(), 12}}) {
    SCOPED_TRACE(name);
    const std::vector<int> s = controls(mesh, count);
    const BiharmonicBasis basis = biharmonic_basis(mesh.V, mesh.F, s);
    ASSERT_EQ(basis.phi.rows(), mesh.V.rows());
    ASSERT_EQ(basis.phi.cols(), count);
    for (int i = 0; i < count; ++i)
      for (int j = 0; j < count; ++j) EXPECT_EQ(basis.phi(s[static_cast<std::size_t>(j)], i), i == j ? 1.0 : 0.0);
    EXPECT_GE(basis.phi.minCoeff(), 0.0);
    EXPECT_LE(basis.phi.maxCoeff(), 1.0);
    // Rows are divided by their sum: Σ = 1 up to N additions' round-off (N·eps ≈ 3e-15).
    EXPECT_LT((basis.phi.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
    EXPECT_EQ(basis.iterations.size(), static_cast<std::size_t>(count));
  }
}

TEST(BiharmonicBasis, BoundedWeightsSatisfyTheKktConditions) {
  for (const auto& [name, mesh] :
       {std::pair{"patch", sflsh::testing::grid_patch()}, std::pair{"blob", sflsh::testing::icosphere(3, true)}}) {
    SCOPED_TRACE(name);
    const std::vector<int> s = controls(mesh, 12);
    BiharmonicOptions raw;
    raw.normalize = false;  // the QP minimizers themselves, before the partition-of-unity division
    const BiharmonicBasis bounded = biharmonic_basis(mesh.V, mesh.F, s, raw);
    raw.bounded = false;
    const BiharmonicBasis free = biharmonic_basis(mesh.V, mesh.F, s, raw);
    const SparseMatrixd Q = biharmonic_energy_matrix(mesh.V, mesh.F);
    for (int i = 0; i < 12; ++i) {
      // The solver stops at multiplier violations ≤ 1e-8 relative; the free-block residual of a stable
      // LDLᵀ solve is far smaller. A wrong active set gives violations of order 1e-3 or more (below).
      EXPECT_LT(kkt_violation(Q, bounded.phi.col(i), s), 1e-7) << "function " << i;
    }
    // The bounds matter: the unconstrained interpolants leave [0, 1], and clamping them is not optimal.
    EXPECT_LT(free.phi.minCoeff(), -1e-3);
    double worst_clamped = 0.0;
    for (int i = 0; i < 12; ++i)
      worst_clamped = std::max(worst_clamped, kkt_violation(Q, free.phi.col(i).cwiseMax(0.0).cwiseMin(1.0), s));
    EXPECT_GT(worst_clamped, 1e-4);
  }
}

TEST(BiharmonicBasis, EnergyIsMinimalAmongFeasibleFunctions) {
  // Each bounded φ_i minimizes φᵀQφ over functions with φ(s_j) = δ_ij and 0 ≤ φ ≤ 1. Two comparisons:
  // the unconstrained interpolant (fewer constraints) has no more energy, and a hat function of the
  // geodesic distance (feasible, not smooth) has more.
  const FieldMesh mesh = sflsh::testing::icosphere(3, true);
  const std::vector<int> s = controls(mesh, 12);
  BiharmonicOptions raw;
  raw.normalize = false;
  const BiharmonicBasis bounded = biharmonic_basis(mesh.V, mesh.F, s, raw);
  raw.bounded = false;
  const BiharmonicBasis free = biharmonic_basis(mesh.V, mesh.F, s, raw);
  const SparseMatrixd Q = biharmonic_energy_matrix(mesh.V, mesh.F);
  const VertexAdjacency adjacency = vertex_adjacency(mesh.F, static_cast<int>(mesh.V.rows()));
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::vector<int> source = {s[i]};
    const Eigen::VectorXd d = edge_distances(mesh.V, adjacency, source);
    double radius = std::numeric_limits<double>::infinity();  // reaches 0 at the nearest other control point
    for (std::size_t j = 0; j < s.size(); ++j)
      if (j != i) radius = std::min(radius, d(s[j]));
    const Eigen::VectorXd hat = (1.0 - d.array() / radius).cwiseMax(0.0).matrix();
    const auto col = static_cast<Eigen::Index>(i);
    const double e_bounded = bounded.phi.col(col).dot(Q * bounded.phi.col(col));
    // Relative 1e-9: the energies are O(10²) sums of cancelling terms; the minimum is exact up to the
    // KKT tolerance 1e-8 of the active-set stop.
    EXPECT_LE(free.phi.col(col).dot(Q * free.phi.col(col)), e_bounded * (1.0 + 1e-9));
    EXPECT_LT(e_bounded, hat.dot(Q * hat)) << "function " << i;
  }
}

TEST(BiharmonicBasis, IsMaximalAtItsControlPointAndDecaysWithDistance) {
  const FieldMesh mesh = sflsh::testing::body_region();
  const std::vector<int> s = controls(mesh, 24);
  const BiharmonicBasis basis = biharmonic_basis(mesh.V, mesh.F, s);
  const VertexAdjacency adjacency = vertex_adjacency(mesh.F, static_cast<int>(mesh.V.rows()));
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto col = static_cast<Eigen::Index>(i);
    Eigen::Index argmax = 0;
    basis.phi.col(col).maxCoeff(&argmax);
    EXPECT_EQ(basis.phi(argmax, col), 1.0);
    // Mean φ_i over vertices closer to s_i than the nearest other control point (its own cell) is far above
    // its mean beyond twice that distance. A factor 5 is loose: smooth local bumps give ratios of ~10–100.
    const std::vector<int> source = {s[i]};
    const Eigen::VectorXd d = edge_distances(mesh.V, adjacency, source);
    double r = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < s.size(); ++j)
      if (j != i) r = std::min(r, d(s[j]));
    double near = 0.0, far = 0.0;
    int n_near = 0, n_far = 0;
    for (Eigen::Index v = 0; v < d.size(); ++v) {
      if (d(v) < 0.5 * r) near += basis.phi(v, col), ++n_near;
      if (d(v) > 2.0 * r) far += basis.phi(v, col), ++n_far;
    }
    // φ_i may plateau at 1 next to its point (bounded weights clamp the others to 0 there, and the
    // normalization makes φ_i exactly 1), but only nearer to s_i than to any other control point.
    for (Eigen::Index v = 0; v < d.size(); ++v)
      if (basis.phi(v, col) == 1.0) {
        EXPECT_LT(d(v), r) << "φ_" << i << " reaches 1 far from its point at vertex " << v;
      }
    ASSERT_GT(n_near, 0);
    ASSERT_GT(n_far, 0);
    EXPECT_GT(near / n_near, 5.0 * far / n_far) << "function " << i;
  }
}

TEST(BiharmonicBasis, SpecialCasesAndDeterminism) {
  const FieldMesh mesh = sflsh::testing::grid_patch();
  const BiharmonicBasis one = biharmonic_basis(mesh.V, mesh.F, {17});
  EXPECT_EQ(one.phi, Eigen::MatrixXd::Ones(mesh.V.rows(), 1));
  // Serial and parallel runs do the same arithmetic per function: bit-identical.
  const std::vector<int> s = controls(mesh, 12);
  BiharmonicOptions serial;
  serial.parallel = false;
  EXPECT_EQ(biharmonic_basis(mesh.V, mesh.F, s).phi, biharmonic_basis(mesh.V, mesh.F, s, serial).phi);
  // Without bounds the interpolants already sum to one (Q·1 = 0): up to the solve's round-off.
  BiharmonicOptions unbounded;
  unbounded.bounded = false;
  EXPECT_LT((biharmonic_basis(mesh.V, mesh.F, s, unbounded).phi.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-9);
}

TEST(BiharmonicBasis, BadControlPointsGiveClearErrors) {
  const FieldMesh mesh = sflsh::testing::grid_patch(8, 4);
  EXPECT_THAT(error_of([&] { biharmonic_basis(mesh.V, mesh.F, {}); }), HasSubstr("no control vertices"));
  EXPECT_THAT(error_of([&] {
                biharmonic_basis(mesh.V, mesh.F, {3, 400});
              }),
              HasSubstr("control vertex 400 (#1) outside"));
  EXPECT_THAT(error_of([&] {
                biharmonic_basis(mesh.V, mesh.F, {3, 5, 3});
              }),
              HasSubstr("control vertex 3 is repeated"));
  // Two disjoint copies of the patch; control points only on the first.
  FieldMesh two;
  two.V.resize(2 * mesh.V.rows(), 3);
  two.V << mesh.V, mesh.V.rowwise() + Eigen::RowVector3d(0, 0, 1);
  two.F.resize(2 * mesh.F.rows(), 3);
  two.F << mesh.F, mesh.F.array() + static_cast<int>(mesh.V.rows());
  EXPECT_THAT(error_of([&] {
                biharmonic_basis(two.V, two.F, {3, 5});
              }),
              HasSubstr("component 1 (containing vertex 45) has no control vertex"));
}

TEST(BiharmonicBasis, SavesAndLoadsTheCache) {
  const FieldMesh mesh = sflsh::testing::grid_patch();
  const BiharmonicBasis basis = biharmonic_basis(mesh.V, mesh.F, controls(mesh, 12));
  const auto path = sflsh::testing::scratch_dir() / "basis.npz";
  save_basis(path, basis);
  const BiharmonicBasis loaded = load_basis(path);
  EXPECT_EQ(loaded.phi, basis.phi);  // float64 stored: bit-exact
  EXPECT_EQ(loaded.control_vertices, basis.control_vertices);
  EXPECT_EQ(loaded.iterations, basis.iterations);
  EXPECT_EQ(loaded.surface_fingerprint, surface_fingerprint(mesh.V, mesh.F));
  EXPECT_TRUE(loaded.bounded && loaded.normalized && loaded.lumping == MassLumping::kVoronoi);
  RowMatrixX3d moved = mesh.V;
  moved(0, 2) += 1e-9;  // any change of the surface changes the fingerprint
  EXPECT_NE(surface_fingerprint(moved, mesh.F), basis.surface_fingerprint);
  npz::write(path, {{"phi", npz::make_f64(basis.phi)}});
  EXPECT_THAT(error_of([&] { load_basis(path); }), HasSubstr("control_vertices"));
}

}  // namespace sflsh
