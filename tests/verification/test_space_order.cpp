// Convergence in space of the full-space discretization (linear tets): a manufactured solution of the static
// elastic problem, whose L² error must fall at second order (and the H¹ seminorm's at first), and the driven
// block of the FEBio comparison refined 2× and 4× in each direction (1,800 → 14,400 → 115,200 tets).
// docs/verification.md.
#include "convergence_log.hpp"
#include "febio_block.hpp"

#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/model/terms.hpp>

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <cstdio>

namespace sflsh::testing {
namespace {

material::SkinMaterial flesh() {
  material::SkinMaterial m;
  m.young_tangent = 5000.0;  // [Pa], the FEBio block's
  m.young_normal = 2000.0;
  return m;
}

/// A cube of side kSide [m] meshed by box_tet_mesh with n cells per side, the flesh material (normal z).
model::Problem cube(int n, double side) {
  const fullspace::MshMesh mesh = fullspace::box_tet_mesh(Eigen::Vector3d::Constant(side), {n, n, n});
  model::Problem p;
  p.rest = mesh.nodes;
  p.tets = mesh.tets;
  p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                        material::make_orthotropic_fung(flesh(), Eigen::Vector3d::UnitZ()));
  p.mass = model::lumped_masses(p.rest, p.tets, 1000.0);
  p.density = 1000.0;
  p.validate();
  return p;
}

// The manufactured displacement u*(X) on the cube [0, L]³: smooth, non-polynomial, every component varying
// along every axis, with strains up to ~6 % (so the Fung factor and the StVK nonlinearity both act).
constexpr double kSide = 0.04;       // [m]
constexpr double kAmplitude = 0.02;  // u* ~ kAmplitude · L

Eigen::Vector3d exact_u(const Eigen::Vector3d& X) {
  const double k = std::numbers::pi / kSide;
  const double a = kAmplitude * kSide;
  return a * Eigen::Vector3d(std::sin(k * X.x()) * std::cos(0.5 * k * X.y()) + 0.5 * X.z() / kSide,
                             std::sin(k * X.y()) * std::sin(k * X.z()),
                             std::cos(k * X.x()) * std::sin(0.5 * k * X.z()) * (1.0 + X.y() / kSide));
}

Eigen::Matrix3d exact_grad(const Eigen::Vector3d& X) {  // ∂u*_i/∂X_j by central differences (error ~1e-12)
  constexpr double d = 1e-6 * kSide;
  Eigen::Matrix3d G;
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d e = d * Eigen::Vector3d::Unit(j);
    G.col(j) = (exact_u(X + e) - exact_u(X - e)) / (2.0 * d);
  }
  return G;
}

/// The body force b = −Div P(I + ∇u*) [N/m³] that makes u* an equilibrium: central differences of P over
/// X (step 1e-4 L: truncation ~1e-8 relative, round-off ~1e-12; far below the discretization error).
Eigen::Vector3d body_force(const Eigen::Vector3d& X, const material::OrthotropicFung& m) {
  constexpr double d = 1e-4 * kSide;
  Eigen::Vector3d div = Eigen::Vector3d::Zero();
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d e = d * Eigen::Vector3d::Unit(j);
    const Eigen::Matrix3d plus = material::dpsi_ortho_fung_dF(Eigen::Matrix3d::Identity() + exact_grad(X + e), m);
    const Eigen::Matrix3d minus = material::dpsi_ortho_fung_dF(Eigen::Matrix3d::Identity() + exact_grad(X - e), m);
    div += (plus.col(j) - minus.col(j)) / (2.0 * d);
  }
  return -div;
}

// The degree-2 rule of four points on a tet (barycentric a, b, b, b and permutations; weights V/4).
constexpr double kQa = 0.5854101966249685;
constexpr double kQb = 0.1381966011250105;

Eigen::Vector4d quadrature_point(int q) {
  Eigen::Vector4d l = Eigen::Vector4d::Constant(kQb);
  l[q] = kQa;
  return l;
}

struct ManufacturedResult {
  double l2 = 0.0;  ///< ‖u_h − u*‖_L² / ‖u*‖_L²
  double h1 = 0.0;  ///< |u_h − u*|_H¹ / |u*|_H¹
  int newton = 0;
};

/// Solves E(x) − f·x stationary with x = X + u* on the cube's boundary (Newton on the interior, exact
/// Hessian, sparse LDLᵀ) and measures the error of the piecewise-linear solution.
ManufacturedResult solve_manufactured(int n) {
  const model::Problem p = cube(n, kSide);
  const material::OrthotropicFung& m = p.tet_material[0];
  const int N = p.num_nodes();
  // Nodal loads f_a = Σ_e ∫ N_a b dV and the boundary values.
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * N);
  for (int e = 0; e < p.num_tets(); ++e) {
    Eigen::Matrix<double, 3, 4> X;
    for (int a = 0; a < 4; ++a) X.col(a) = p.rest.row(p.tets(e, a)).transpose();
    const double volume = std::abs((X.col(1) - X.col(0)).cross(X.col(2) - X.col(0)).dot(X.col(3) - X.col(0))) / 6.0;
    for (int q = 0; q < 4; ++q) {
      const Eigen::Vector4d l = quadrature_point(q);
      const Eigen::Vector3d b = body_force(X * l, m);
      for (int a = 0; a < 4; ++a) f.segment<3>(3 * p.tets(e, a)) += 0.25 * volume * l[a] * b;
    }
  }
  std::vector<Eigen::Index> free_index(static_cast<std::size_t>(3 * N), -1);
  Eigen::Index num_free = 0;
  Eigen::VectorXd x(3 * N);
  for (int v = 0; v < N; ++v) {
    const Eigen::Vector3d X = p.rest.row(v).transpose();
    x.segment<3>(3 * v) = X + exact_u(X);  // boundary values; the interior starts from the interpolant
    const bool boundary = (X.array() < 1e-12).any() || (X.array() > kSide - 1e-12).any();
    if (!boundary)
      for (int c = 0; c < 3; ++c) free_index[static_cast<std::size_t>(3 * v + c)] = num_free++;
  }
  const auto subset = model::TermSubset::whole(p);
  model::ElasticTerm elastic(p, subset);
  elastic.set_projection(material::HessianProjection::kNone);
  struct Sink final : model::HessianSink {
    Sink(const model::Problem& problem, const std::vector<Eigen::Index>& index) : p(problem), free(index) {}
    void add_tet(std::size_t /*k*/, int e, const material::Matrix12d& block) override {
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) add(p.tets(e, a), p.tets(e, b), block.block<3, 3>(3 * a, 3 * b));
    }
    void add_node(int node, const Eigen::Matrix3d& block) override { add(node, node, block); }
    void add(int i, int j, const Eigen::Matrix3d& block) {
      for (int r = 0; r < 3; ++r) {
        const Eigen::Index row = free[static_cast<std::size_t>(3 * i + r)];
        if (row < 0) continue;
        for (int c = 0; c < 3; ++c) {
          const Eigen::Index col = free[static_cast<std::size_t>(3 * j + c)];
          if (col >= 0) entries.emplace_back(row, col, block(r, c));
        }
      }
    }
    const model::Problem& p;
    const std::vector<Eigen::Index>& free;
    std::vector<Eigen::Triplet<double>> entries;
  };
  ManufacturedResult out;
  for (;; ++out.newton) {
    require(out.newton < 20, "manufactured solution: Newton did not converge on {} cells per side", n);
    Eigen::VectorXd g = -f;
    require(elastic.add_gradient(x, g), "manufactured solution: gradient failed");
    Sink sink(p, free_index);
    require(elastic.add_hessian(x, sink), "manufactured solution: Hessian failed");
    Eigen::VectorXd rhs(num_free);
    for (std::size_t d = 0; d < free_index.size(); ++d)
      if (free_index[d] >= 0) rhs[free_index[d]] = -g[static_cast<Eigen::Index>(d)];
    Eigen::SparseMatrix<double> H(num_free, num_free);
    H.setFromTriplets(sink.entries.begin(), sink.entries.end());
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
    require(solver.info() == Eigen::Success, "manufactured solution: singular Hessian");
    const Eigen::VectorXd dx = solver.solve(rhs);
    for (std::size_t d = 0; d < free_index.size(); ++d)
      if (free_index[d] >= 0) x[static_cast<Eigen::Index>(d)] += dx[free_index[d]];
    if (dx.lpNorm<Eigen::Infinity>() < 1e-13 * kSide) break;  // quadratic convergence: the next is round-off
  }
  // Errors by the same four-point rule (the L² error of a linear interpolant is O(h²), its gradient's O(h)).
  double l2 = 0.0, l2_exact = 0.0, h1 = 0.0, h1_exact = 0.0;
  for (int e = 0; e < p.num_tets(); ++e) {
    Eigen::Matrix<double, 3, 4> X, u;
    for (int a = 0; a < 4; ++a) {
      X.col(a) = p.rest.row(p.tets(e, a)).transpose();
      u.col(a) = x.segment<3>(3 * p.tets(e, a)) - X.col(a);
    }
    Eigen::Matrix3d Dm;
    for (int a = 0; a < 3; ++a) Dm.col(a) = X.col(a + 1) - X.col(0);
    const double volume = std::abs(Dm.determinant()) / 6.0;
    Eigen::Matrix3d Du;
    for (int a = 0; a < 3; ++a) Du.col(a) = u.col(a + 1) - u.col(0);
    const Eigen::Matrix3d grad_h = Du * Dm.inverse();
    for (int q = 0; q < 4; ++q) {
      const Eigen::Vector4d l = quadrature_point(q);
      const Eigen::Vector3d Xq = X * l;
      const Eigen::Vector3d exact = exact_u(Xq);
      const Eigen::Matrix3d grad = exact_grad(Xq);
      l2 += 0.25 * volume * (u * l - exact).squaredNorm();
      l2_exact += 0.25 * volume * exact.squaredNorm();
      h1 += 0.25 * volume * (grad_h - grad).squaredNorm();
      h1_exact += 0.25 * volume * grad.squaredNorm();
    }
  }
  out.l2 = std::sqrt(l2 / l2_exact);
  out.h1 = std::sqrt(h1 / h1_exact);
  return out;
}

TEST(SpaceOrder, ManufacturedStaticSolutionConvergesAtSecondOrderInL2) {
  const std::vector<int> cells = {4, 8, 16};
  std::vector<double> h, l2, h1;
  for (int n : cells) {
    const ManufacturedResult r = solve_manufactured(n);
    h.push_back(kSide / n);
    l2.push_back(r.l2);
    h1.push_back(r.h1);
    std::printf("[ measured ] manufactured solution, %d³ cells (%d tets): L² error %.3e, H¹ error %.3e, %d Newton\n", n,
                6 * n * n * n, r.l2, r.h1, r.newton);
  }
  const double l2_order = observed_order(l2[1], l2[2]);
  const double h1_order = observed_order(h1[1], h1[2]);
  std::printf("[ measured ] observed orders: L² %.2f, %.2f; H¹ %.2f, %.2f\n", observed_order(l2[0], l2[1]), l2_order,
              observed_order(h1[0], h1[1]), h1_order);
  log_convergence("space_manufactured", "l2", h, l2);
  log_convergence("space_manufactured", "h1", h, h1);
  // Linear tets: O(h²) in L², O(h) in the H¹ seminorm for a smooth solution. The finer pair is in the asymptotic
  // range (four to sixteen cells per half wave of u*); ±0.3 separates the orders and tolerates the mesh's
  // anisotropic split (Kuhn tets) entering at the coarser level.
  EXPECT_NEAR(l2_order, 2.0, 0.3);
  EXPECT_NEAR(h1_order, 1.0, 0.3);
  EXPECT_LT(l2[2], 0.05);  // and the solution converges onto u*, not elsewhere
}

/// The top-face displacement of the FEBio block (10 × 10 × 3 cm) held at the bone and sagging under gravity,
/// static, on 10 × 10 × 3 cells refined 2× and 4× in each direction; per level, u of the coarse mesh's top-face
/// nodes (which exist in every refinement). `sliding_sides`: the four sides slide on their planes (zero normal
/// displacement) instead of being free.
struct BlockRefinement {
  std::vector<Eigen::VectorXd> top;  ///< [m] per level
  std::vector<double> h;             ///< [m] the cell size per level
  double order = 0.0;                ///< observed order of the top face's change between levels
  std::vector<double> change;        ///< RMS change 1→2×, 2→4× relative to the RMS top-face displacement
};

BlockRefinement refine_block(bool sliding_sides) {
  const Eigen::Vector3d size(0.1, 0.1, 0.03);
  BlockRefinement out;
  for (int r : {1, 2, 4}) {
    const std::array<int, 3> cells = {10 * r, 10 * r, 3 * r};
    const fullspace::MshMesh mesh = fullspace::box_tet_mesh(size, cells);
    model::Problem p;
    p.rest = mesh.nodes;
    p.tets = mesh.tets;
    p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                          material::make_orthotropic_fung(flesh(), Eigen::Vector3d::UnitZ()));
    p.mass = model::lumped_masses(p.rest, p.tets, 1000.0);
    p.density = 1000.0;
    p.gravity = Eigen::Vector3d(3.0, 0.0, -9.81);  // [m/s²]: a tilted block, so it shears as well as sags
    for (int v : mesh.node_groups.at("zmin")) p.dirichlet.add(v, 7u);
    if (sliding_sides) {
      for (const char* side : {"xmin", "xmax"})
        for (int v : mesh.node_groups.at(side)) p.dirichlet.add(v, 1u);
      for (const char* side : {"ymin", "ymax"})
        for (int v : mesh.node_groups.at(side)) p.dirichlet.add(v, 2u);
    }
    p.validate();
    fullspace::FullSpaceOptions options;
    options.quasi_static = true;
    options.default_snes_rtol = 1e-12;
    options.default_snes_atol = 1e-14;
    options.default_ksp_rtol = 1e-12;
    fullspace::FullSpaceSolver solver(p, MPI_COMM_SELF, options);
    model::State s;
    s.x = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
    s.w = Eigen::VectorXd::Zero(p.num_dofs());
    solver.initialize(s);
    solver.step(1.0);
    Eigen::VectorXd u(3 * 11 * 11);
    for (int j = 0; j <= 10; ++j)
      for (int i = 0; i <= 10; ++i) {
        const int v = r * i + (cells[0] + 1) * (r * j + (cells[1] + 1) * cells[2]);
        u.segment<3>(3 * (i + 11 * j)) = solver.state().x.segment<3>(3 * v) - p.rest.row(v).transpose();
      }
    out.top.push_back(u);
    out.h.push_back(0.01 / r);
    std::printf("[ measured ] block under gravity (%s sides), %d tets: mean top-face sag %.4e m\n",
                sliding_sides ? "sliding" : "free", p.num_tets(), u(Eigen::seqN(2, 121, 3)).mean());
  }
  // RMS over the top face of the change between levels, relative to the RMS top-face displacement.
  auto rms = [](const Eigen::VectorXd& v) { return v.norm() / std::sqrt(static_cast<double>(v.size() / 3)); };
  const double scale = rms(out.top[2]);
  out.change = {rms(out.top[0] - out.top[1]) / scale, rms(out.top[1] - out.top[2]) / scale};
  out.order = observed_order(out.change[0], out.change[1]);
  std::printf(
      "[ measured ] block top face (%s sides): change 1→2× %.3e, 2→4× %.3e of its displacement; observed "
      "order %.2f\n",
      sliding_sides ? "sliding" : "free", out.change[0], out.change[1], out.order);
  log_convergence(sliding_sides ? "space_block_sliding" : "space_block", "top_face", {out.h[0], out.h[1]}, out.change);
  return out;
}

TEST(SpaceOrder, BlockWithSlidingSidesConvergesAtSecondOrder) {
  // Sliding sides mirror the block across each side plane: the clamped bottom and the free top continue flat
  // through the sides, there is no edge where a clamped face meets a free one, and the solution is smooth. Linear
  // tets then converge at second order in the displacement. Measured 1.69 over the top face (the mean sag alone:
  // 2.2), still short of 2 with 3 to 12 cells through the thickness; the bounds [1.5, 2.35] hold second order
  // and exclude the first order of a consistency error and the free-sided block's 1.11 (the test below).
  const BlockRefinement b = refine_block(true);
  EXPECT_GT(b.order, 1.5);
  EXPECT_LT(b.order, 2.35);
  EXPECT_LT(b.change[1], 0.05);
}

TEST(SpaceOrder, BlockTopFaceUnderGravityConvergesUnderRefinement) {
  // The FEBio comparison's block as it is, with free sides. Where the clamped bottom meets a free side the
  // displacement is singular, u ~ r^λ with λ ≈ 0.78 for an isotropic solid of ν = 0.2 (Williams' clamped–free
  // right-angle wedge, (3 − 4ν) sin²(λπ/2) = 4(1 − ν)² − λ²), lower for this material, whose normal modulus is
  // 0.4 of the tangent one. Every displacement then converges at most at 2λ, and at these resolutions (3 to 12
  // cells through the thickness) slower: measured 1.11 over the top face (1.69 with sliding sides, the test
  // above). So: clearly convergent (order > 0.8: the change halves between levels),
  // not above the smooth rate, and the finest change small.
  const BlockRefinement b = refine_block(false);
  EXPECT_GT(b.order, 0.8);
  EXPECT_LT(b.order, 2.35);
  EXPECT_LT(b.change[1], 0.05);
}

}  // namespace
}  // namespace sflsh::testing
