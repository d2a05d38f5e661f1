// The PETSc backward-Euler integrator on canonical problems: patch test, static sag under refinement,
// step rejection, rigid motion through the node maps, and PETSc's own Jacobian check.
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <petscsys.h>

#include <cmath>

namespace sflsh::fullspace {
namespace {

material::SkinMaterial skin(double young_tangent = 5000.0, double young_normal = 2000.0) {
  material::SkinMaterial m;
  m.young_tangent = young_tangent;
  m.young_normal = young_normal;
  return m;
}

/// A problem on a structured box mesh with a homogeneous material.
Problem box_problem(const Eigen::Vector3d& size, std::array<int, 3> cells, double density,
                    const material::SkinMaterial& material = skin()) {
  const MshMesh mesh = box_tet_mesh(size, cells);
  Problem p;
  p.rest = mesh.nodes;
  p.tets = mesh.tets;
  p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                        material::make_orthotropic_fung(material, Eigen::Vector3d::UnitZ()));
  p.mass = lumped_masses(p.rest, p.tets, density);
  p.density = density;
  return p;
}

std::vector<int> group(const Eigen::Vector3d& size, std::array<int, 3> cells, const std::string& name) {
  return box_tet_mesh(size, cells).node_groups.at(name);
}

TEST(FullSpaceSolver, PatchTestAffineBoundaryGivesAffineSolution) {
  // Every boundary node prescribed on x ↦ (I + G)x: the exact solution of any homogeneous hyperelastic
  // material is the affine map (uniform F, divergence-free stress), whatever the nonlinearity.
  const Eigen::Vector3d size(0.1, 0.08, 0.06);
  const std::array<int, 3> cells{3, 3, 2};
  Problem p = box_problem(size, cells, 0.0);
  Eigen::Matrix3d G;
  G << 0.05, 0.02, -0.01, 0.00, -0.03, 0.04, 0.01, 0.02, 0.06;
  std::vector<char> boundary(static_cast<std::size_t>(p.num_nodes()), 0);
  for (const char* face : {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"}) {
    for (int v : group(size, cells, face)) boundary[static_cast<std::size_t>(v)] = 1;
  }
  int interior = 0;
  for (int v = 0; v < p.num_nodes(); ++v) {
    if (!boundary[static_cast<std::size_t>(v)]) {
      ++interior;
      continue;
    }
    const Eigen::Vector3d u = G * p.rest.row(v).transpose();
    for (int k = 0; k < 3; ++k) {
      const double value = u[k];
      p.dirichlet.drives.push_back({[value](double) { return value; }, [](double) { return 0.0; }});
      p.dirichlet.add(v, 1u << k, static_cast<int>(p.dirichlet.drives.size()) - 1);
    }
  }
  ASSERT_GT(interior, 0);
  p.validate();
  FullSpaceOptions options;
  options.quasi_static = true;
  FullSpaceSolver solver(p, PETSC_COMM_WORLD, options);
  State s;
  s.x = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  s.w = Eigen::VectorXd::Zero(p.num_dofs());
  solver.initialize(s);
  const StepStats stats = solver.step(1.0);
  EXPECT_GE(stats.newton_iterations, 1);
  double worst = 0.0;
  for (int v = 0; v < p.num_nodes(); ++v) {
    const Eigen::Vector3d expected = (Eigen::Matrix3d::Identity() + G) * p.rest.row(v).transpose();
    worst = std::max(worst, (solver.state().x.segment<3>(3 * v) - expected).norm());
  }
  // Newton converges to rtol 1e-8 of the initial residual; the node error is that fraction of the
  // ~5 mm boundary displacement and far below 1e-9 m.
  EXPECT_LT(worst, 1e-9);
}

/// Tip deflection of a cantilever (fixed at x = 0) sagging under gravity, quasi-static.
double cantilever_tip_sag(int refinement) {
  const Eigen::Vector3d size(0.2, 0.04, 0.04);
  const std::array<int, 3> cells{5 * refinement, refinement, refinement};
  Problem p = box_problem(size, cells, 1000.0, skin(20000.0, 20000.0));
  for (int v : group(size, cells, "xmin")) p.dirichlet.add(v, 7u);
  p.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  p.validate();
  FullSpaceOptions options;
  options.quasi_static = true;
  FullSpaceSolver solver(p, PETSC_COMM_WORLD, options);
  State s;
  s.x = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  s.w = Eigen::VectorXd::Zero(p.num_dofs());
  solver.initialize(s);
  solver.step(1.0);
  double sag = 0.0;
  const std::vector<int> tip = group(size, cells, "xmax");
  for (int v : tip) sag += solver.state().x[3 * v + 1] - p.rest(v, 1);
  return sag / static_cast<double>(tip.size());
}

TEST(FullSpaceSolver, StaticSagConvergesUnderRefinement) {
  const double s1 = cantilever_tip_sag(1);
  const double s2 = cantilever_tip_sag(2);
  const double s4 = cantilever_tip_sag(4);
  EXPECT_LT(s1, 0.0);
  // Linear tets are too stiff in bending: the sag grows with refinement and the increments shrink
  // (first-order convergence of the energy norm halves them at each refinement; 0.7 leaves margin).
  EXPECT_LT(s2, s1);
  EXPECT_LT(s4, s2);
  EXPECT_LT(std::abs(s4 - s2), 0.7 * std::abs(s2 - s1));
}

/// A node map that moves the whole mesh rigidly: p = R(t) x + c(t).
class RigidTrajectory : public NodeTrajectory {
 public:
  RigidTrajectory(int n, Eigen::Vector3d acceleration, double spin) : n_(n), a_(std::move(acceleration)), spin_(spin) {}
  int num_nodes() const override { return n_; }
  void evaluate(double t, NodeFrame& frame, NodeFrame* rate) const override {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(spin_ * t, Eigen::Vector3d::UnitY()).toRotationMatrix();
    Eigen::Matrix3d Rdot;
    Rdot << -std::sin(spin_ * t), 0, std::cos(spin_ * t), 0, 0, 0, -std::cos(spin_ * t), 0, -std::sin(spin_ * t);
    Rdot *= spin_;
    frame.A.assign(static_cast<std::size_t>(n_), R);
    frame.d = RowMatrixX3d(n_, 3);
    frame.d.rowwise() = (0.5 * a_ * t * t).transpose();
    if (rate) {
      rate->A.assign(static_cast<std::size_t>(n_), Rdot);
      rate->d = RowMatrixX3d(n_, 3);
      rate->d.rowwise() = (a_ * t).transpose();
    }
  }

 private:
  int n_;
  Eigen::Vector3d a_;
  double spin_;
};

TEST(FullSpaceSolver, UniformAccelerationOfTheFrameWithMatchingGravityStaysUndeformed) {
  // Equivalence principle: a frame accelerating with g carries a free body without deforming it.
  const Eigen::Vector3d size(0.05, 0.05, 0.05);
  Problem p = box_problem(size, {2, 2, 2}, 1000.0);
  const Eigen::Vector3d g(0.0, -9.81, 0.0);
  p.gravity = g;
  p.trajectory = std::make_shared<RigidTrajectory>(p.num_nodes(), g, 0.0);
  p.validate();
  FullSpaceSolver solver(p, PETSC_COMM_WORLD);
  solver.initialize(initial_state(p, 0.0));
  const double h = 1.0 / 60.0;
  const int steps = 10;
  for (int k = 0; k < steps; ++k) solver.step(h);
  // Backward Euler's own free fall is v_{n+1} = v_n + h g, p_{n+1} = p_n + h v_{n+1}, i.e. p_n = ½ g h² n(n+1),
  // while the frame follows ½ g t_n² = ½ g h² n²: the body lags the frame rigidly by ½ g h² n in the unposed
  // coordinates, and does not deform.
  const Eigen::Vector3d lag = 0.5 * g * h * h * steps;
  for (int v = 0; v < p.num_nodes(); ++v) {
    const Eigen::Vector3d u = solver.state().x.segment<3>(3 * v) - p.rest.row(v).transpose();
    EXPECT_LT((u - lag).lpNorm<Eigen::Infinity>(), 1e-9) << "node " << v;
  }
  EXPECT_LT(energies(p, solver.state()).elastic, 1e-12);
}

TEST(FullSpaceSolver, SpinningFrameStretchesTheBodyOutwards) {
  // A body carried around a vertical axis through its corner feels the centrifugal load: nodes move
  // outwards in the rotating frame and stay finite.
  const Eigen::Vector3d size(0.1, 0.02, 0.02);
  const std::array<int, 3> cells{5, 1, 1};
  Problem p = box_problem(size, cells, 1000.0);
  for (int v : group(size, cells, "xmin")) p.dirichlet.add(v, 7u);
  p.trajectory = std::make_shared<RigidTrajectory>(p.num_nodes(), Eigen::Vector3d::Zero(), 6.0);
  p.validate();
  FullSpaceSolver solver(p, PETSC_COMM_WORLD);
  solver.initialize(initial_state(p, 0.0));
  for (int k = 0; k < 60; ++k) solver.step(1.0 / 60.0);
  double stretch = 0.0;
  for (int v : group(size, cells, "xmax")) stretch += solver.state().x[3 * v] - p.rest(v, 0);
  EXPECT_GT(stretch, 0.0);
  EXPECT_TRUE(solver.state().x.allFinite());
}

TEST(FullSpaceSolver, HugeStepIsRecoveredBySubstepsOrFailsLoudly) {
  // A soft bar hit by a violent prescribed jerk in one large step: the integrator must either recover
  // (substeps) or throw sflsh::Error, never return non-finite values.
  const Eigen::Vector3d size(0.1, 0.02, 0.02);
  const std::array<int, 3> cells{6, 1, 1};
  Problem p = box_problem(size, cells, 1000.0, skin(500.0, 500.0));
  p.dirichlet.drives.push_back({[](double t) { return 0.3 * t; }, [](double) { return 0.3; }});
  for (int v : group(size, cells, "xmin")) p.dirichlet.add(v, 1u, 0);
  for (int v : group(size, cells, "xmin")) p.dirichlet.add(v, 6u);
  p.validate();
  FullSpaceSolver solver(p, PETSC_COMM_WORLD);
  solver.initialize(initial_state(p, 0.0));
  try {
    const StepStats stats = solver.step(0.5);
    EXPECT_TRUE(solver.state().x.allFinite());
    EXPECT_GE(stats.substeps, 1);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("backward Euler failed"), std::string::npos) << e.what();
  }
}

TEST(FullSpaceSolver, InvertedInitialElementRecovers) {
  // One node of the start state pushed through its opposite face: StVK has no barrier, the projected
  // Newton with energy line search pulls it back to a valid equilibrium.
  const Eigen::Vector3d size(0.05, 0.05, 0.05);
  const std::array<int, 3> cells{2, 2, 2};
  Problem p = box_problem(size, cells, 1000.0);
  for (int v : group(size, cells, "zmin")) p.dirichlet.add(v, 7u);
  p.validate();
  FullSpaceSolver solver(p, PETSC_COMM_WORLD);
  State s = initial_state(p, 0.0);
  // The centre node (interior) pushed 1.5 cell widths along z, through the top nodes' plane.
  int centre = -1;
  for (int v = 0; v < p.num_nodes(); ++v) {
    if ((p.rest.row(v) - 0.5 * size.transpose()).norm() < 1e-9) centre = v;
  }
  ASSERT_GE(centre, 0);
  s.x[3 * centre + 2] += 1.5 * size.z() / 2.0;
  solver.initialize(s);
  for (int k = 0; k < 30; ++k) solver.step(1.0 / 60.0);
  EXPECT_TRUE(solver.state().x.allFinite());
  EXPECT_LT(std::abs(solver.state().x[3 * centre + 2] - p.rest(centre, 2)), 0.5 * size.z() / 2.0);
}

}  // namespace
}  // namespace sflsh::fullspace
