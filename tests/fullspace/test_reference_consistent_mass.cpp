// The SUNDIALS reference with the consistent mass (M_y ẏ = f, reference_integrator.hpp): its Jacobian and mass
// matrix against the equations of motion, agreement with the lumped path where the two coincide (rigid motion,
// mesh refinement), energy conservation of a free oscillation, and one-line errors for bad configurations.
#include "error_of.hpp"
#include "total_energy.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/material/skin_material.hpp>
#include <sflsh/model/mass.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

namespace sflsh::fullspace {
namespace {

using sflsh::testing::error_of;

constexpr double kDensity = 1000.0;  // [kg/m³]

/// A box of `cells` Kuhn-split cubes with our skin material (Y_t = 5 kPa, Y_n = 2 kPa, normal z), ρ = 1000.
Problem box_problem(const Eigen::Vector3d& size, std::array<int, 3> cells, model::MassKind kind,
                    double young_scale = 1.0) {
  const MshMesh mesh = box_tet_mesh(size, cells);
  Problem p;
  p.rest = mesh.nodes;
  p.tets = mesh.tets;
  material::SkinMaterial skin;
  skin.young_tangent = 5000.0 * young_scale;
  skin.young_normal = 2000.0 * young_scale;
  p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                        material::make_orthotropic_fung(skin, Eigen::Vector3d::UnitZ()));
  p.mass = lumped_masses(p.rest, p.tets, kDensity);
  p.density = kDensity;
  p.mass_kind = kind;
  return p;
}

/// Clamps every node of the box's x = 0 face (all components).
void clamp_xmin(Problem& p, const Eigen::Vector3d& size, std::array<int, 3> cells) {
  const MshMesh mesh = box_tet_mesh(size, cells);
  for (int v : mesh.node_groups.at("xmin")) p.dirichlet.add(v, 7u);
}

/// p = A(t) x + d(t), A(t) = R_z(ω t), d(t) = a t²/2 for every node.
class SpinningFrame : public NodeTrajectory {
 public:
  SpinningFrame(int num_nodes, double spin, const Eigen::Vector3d& acceleration)
      : n_(num_nodes), spin_(spin), acceleration_(acceleration) {}
  int num_nodes() const override { return n_; }
  void evaluate(double t, NodeFrame& frame, NodeFrame* rate) const override {
    const double c = std::cos(spin_ * t), s = std::sin(spin_ * t);
    Eigen::Matrix3d A, dA;
    A << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
    dA << -s, -c, 0.0, c, -s, 0.0, 0.0, 0.0, 0.0;
    frame.A.assign(static_cast<std::size_t>(n_), A);
    frame.d = (0.5 * t * t * acceleration_).transpose().replicate(n_, 1);
    if (rate != nullptr) {
      rate->A.assign(static_cast<std::size_t>(n_), spin_ * dA);
      rate->d = (t * acceleration_).transpose().replicate(n_, 1);
    }
  }

 private:
  int n_;
  double spin_;
  Eigen::Vector3d acceleration_;
};

using sflsh::testing::total_energy;

const Eigen::Vector3d kBar(0.1, 0.02, 0.02);  // [m]
constexpr std::array<int, 3> kBarCells{4, 1, 1};

TEST(ReferenceConsistentMass, JacobianMatchesFiniteDifferencesAndMassIsTheConsistentMatrix) {
  // A deformed, moving state under a spinning, accelerating frame with a clamped end, under gravity.
  Problem p = box_problem(kBar, kBarCells, model::MassKind::consistent);
  clamp_xmin(p, kBar, kBarCells);
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.trajectory = std::make_shared<SpinningFrame>(p.num_nodes(), 1.3, Eigen::Vector3d(1.0, -2.0, 0.5));
  p.validate();
  ReferenceIntegrator integrator(p);
  const int nx = p.num_dofs();
  Eigen::VectorXd y(2 * nx);
  y.head(nx) = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), nx) + 0.002 * Eigen::VectorXd::Random(nx);
  y.tail(nx) = 0.05 * Eigen::VectorXd::Random(nx);
  const double t = 0.3;
  const Eigen::MatrixXd J = Eigen::MatrixXd(integrator.jacobian(t, y));
  Eigen::MatrixXd fd(2 * nx, 2 * nx);
  const double eps = 1e-7;
  for (int c = 0; c < 2 * nx; ++c) {
    Eigen::VectorXd yp = y, ym = y;
    yp[c] += eps;
    ym[c] -= eps;
    fd.col(c) = (integrator.rhs(t, yp) - integrator.rhs(t, ym)) / (2.0 * eps);
  }
  const double scale = fd.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.0);
  EXPECT_LT((J - fd).cwiseAbs().maxCoeff() / scale, 1e-6);

  // M_y = diag(I, M ⊗ I₃) on free components, identity rows and columns on prescribed ones.
  const Eigen::MatrixXd My = Eigen::MatrixXd(integrator.mass_matrix());
  const Eigen::MatrixXd M = Eigen::MatrixXd(p.mass_matrix());
  const std::vector<char> fixed = p.dirichlet.mask(p.num_nodes());
  EXPECT_TRUE(My.topLeftCorner(nx, nx).isIdentity(0.0));
  EXPECT_EQ(My.topRightCorner(nx, nx).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(My.bottomLeftCorner(nx, nx).cwiseAbs().maxCoeff(), 0.0);
  for (int r = 0; r < nx; ++r) {
    for (int c = 0; c < nx; ++c) {
      const bool free_pair = fixed[static_cast<std::size_t>(r)] == 0 && fixed[static_cast<std::size_t>(c)] == 0;
      const double expected = free_pair ? (r % 3 == c % 3 ? M(r / 3, c / 3) : 0.0) : (r == c ? 1.0 : 0.0);
      ASSERT_EQ(My(nx + r, nx + c), expected) << r << ", " << c;
    }
  }
}

TEST(ReferenceConsistentMass, RightSideIsTheLumpedAccelerationTimesTheLumpedMass) {
  // Identity maps, fixed (undriven) constraints: the prescribed accelerations vanish, so on free components
  // f_w = −∇E + m g = m ẇ_lumped, while the x rows are the same ẋ = w in both. The x = 0 face is held in x and z
  // only: its nodes' free y components follow the same rule (the lumped path's component-wise constraints).
  Problem lumped = box_problem(kBar, kBarCells, model::MassKind::lumped);
  const MshMesh mesh = box_tet_mesh(kBar, kBarCells);
  for (int v : mesh.node_groups.at("xmin")) lumped.dirichlet.add(v, 5u);
  lumped.gravity = Eigen::Vector3d(0.0, -3.0, -9.81);
  lumped.validate();
  Problem consistent = lumped;
  consistent.mass_kind = model::MassKind::consistent;
  consistent.validate();
  ReferenceIntegrator a(lumped), b(consistent);
  const int nx = lumped.num_dofs();
  Eigen::VectorXd y(2 * nx);
  y.head(nx) = Eigen::Map<const Eigen::VectorXd>(lumped.rest.data(), nx) + 0.003 * Eigen::VectorXd::Random(nx);
  y.tail(nx) = 0.1 * Eigen::VectorXd::Random(nx);
  const Eigen::VectorXd fa = a.rhs(0.2, y), fb = b.rhs(0.2, y);
  EXPECT_LT((fa.head(nx) - fb.head(nx)).cwiseAbs().maxCoeff(), 1e-15);
  const std::vector<char> fixed = lumped.dirichlet.mask(lumped.num_nodes());
  double worst = 0.0, scale = 0.0;
  for (int d = 0; d < nx; ++d) {
    if (fixed[static_cast<std::size_t>(d)] != 0) {
      EXPECT_EQ(fb[nx + d], 0.0);
      continue;
    }
    worst = std::max(worst, std::abs(lumped.mass[d / 3] * fa[nx + d] - fb[nx + d]));
    scale = std::max(scale, std::abs(fb[nx + d]));
  }
  ASSERT_GT(scale, 0.0);
  EXPECT_LT(worst, 1e-12 * scale);
}

TEST(ReferenceConsistentMass, RigidMotionIsTheSameAsWithLumpedMasses) {
  // The consistent matrix's row sums are the lumped masses, so a rigid motion (free fall; a spinning,
  // accelerating frame whose inertial force gravity cancels) is exact with either.
  Problem p = box_problem(kBar, {2, 1, 1}, model::MassKind::consistent);
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.validate();
  ReferenceIntegrator falling(p);
  falling.initialize(initial_state(p, 0.0));
  const double t = 0.5;
  const State s = falling.advance_to(t);
  for (int v = 0; v < p.num_nodes(); ++v) {
    const Eigen::Vector3d expected = p.rest.row(v).transpose() + 0.5 * t * t * p.gravity;
    EXPECT_LT((s.x.segment<3>(3 * v) - expected).norm(), 1e-9) << "node " << v;
    EXPECT_LT((s.w.segment<3>(3 * v) - t * p.gravity).norm(), 1e-9) << "node " << v;
  }
  EXPECT_GT(falling.stats().mass_solves, 0);

  // d(t) = a t²/2 with g = a: nothing deforms, one node even prescribed (its prescribed acceleration enters
  // the free rows through M_FC and must balance).
  Problem q = box_problem(kBar, {2, 1, 1}, model::MassKind::consistent);
  const Eigen::Vector3d a(0.5, -1.0, 2.0);
  q.trajectory = std::make_shared<SpinningFrame>(q.num_nodes(), 0.0, a);
  q.gravity = a;
  q.dirichlet.add(0, 7u);
  q.validate();
  ReferenceIntegrator carried(q);
  carried.initialize(initial_state(q, 0.0));
  const Eigen::VectorXd X = Eigen::Map<const Eigen::VectorXd>(q.rest.data(), q.num_dofs());
  for (double time : {0.1, 0.5, 1.0}) {
    const State sk = carried.advance_to(time);
    EXPECT_LT((sk.x - X).lpNorm<Eigen::Infinity>(), 1e-9) << "t = " << time;
    for (int v = 0; v < q.num_nodes(); ++v) EXPECT_LT((sk.w.segment<3>(3 * v) - a * time).norm(), 1e-8) << v;
  }
}

/// The axial displacement [m] of a clamped bar's free end (mean over its nodes), every 5 ms for 0.4 s, with the
/// bar released from the axial velocity of its first mode, v = 1 cm/s · sin(πx/2L).
std::vector<double> axial_ringing(int cells, model::MassKind kind) {
  const std::array<int, 3> shape{cells, 1, 1};
  Problem p = box_problem(kBar, shape, kind);
  clamp_xmin(p, kBar, shape);
  p.validate();
  State s = initial_state(p, 0.0);
  for (int v = 0; v < p.num_nodes(); ++v) s.w[3 * v] = 0.01 * std::sin(0.5 * M_PI * p.rest(v, 0) / kBar.x());
  for (int dof : p.dirichlet.dof) s.w[dof] = 0.0;
  ReferenceOptions options;
  options.rtol = 1e-8;
  options.atol = 1e-12;
  ReferenceIntegrator integrator(p, options);
  integrator.initialize(s);
  const MshMesh mesh = box_tet_mesh(kBar, shape);
  const std::vector<int>& tip = mesh.node_groups.at("xmax");
  std::vector<double> out;
  for (int k = 1; k <= 80; ++k) {
    const State sk = integrator.advance_to(0.005 * k);
    double sum = 0.0;
    for (int v : tip) sum += sk.x[3 * v] - p.rest(v, 0);
    out.push_back(sum / static_cast<double>(tip.size()));
  }
  return out;
}

TEST(ReferenceConsistentMass, LumpedAndConsistentConvergeTogetherUnderRefinement) {
  // Axial ringing of a clamped bar (first mode ≈ 5.6 Hz, ~2 periods): lumping lowers the frequencies by
  // ~(kh)²/24, the consistent mass raises them by ~(kh)²/12, so the gap between the two trajectories is a phase
  // drift that shrinks as the cells along the bar are halved: both are the same dynamics in the limit.
  // Measured: 13.4 % of the amplitude at 4 cells, 4.3 % at 8, 2.1 % at 16 (the single cell across the bar,
  // which is not refined here, keeps a floor); 4 → 8 cells is the clean O(h²) part.
  double previous = std::numeric_limits<double>::infinity();
  for (int cells : {4, 8}) {
    const std::vector<double> lumped = axial_ringing(cells, model::MassKind::lumped);
    const std::vector<double> consistent = axial_ringing(cells, model::MassKind::consistent);
    double gap = 0.0, amplitude = 0.0;
    for (std::size_t k = 0; k < lumped.size(); ++k) {
      gap = std::max(gap, std::abs(lumped[k] - consistent[k]));
      amplitude = std::max(amplitude, std::abs(consistent[k]));
    }
    std::printf("[ measured ] %2d cells: lumped vs consistent %.3e of the amplitude %.3e m\n", cells, gap / amplitude,
                amplitude);
    EXPECT_GT(amplitude, 1e-4);  // it really rang
    EXPECT_LT(gap, 0.5 * previous) << cells << " cells";
    previous = gap;
  }
}

TEST(ReferenceConsistentMass, FreeOscillationConservesEnergy) {
  // Clamped bar, no gravity, released with a transverse velocity ramp: the kinetic energy ½wᵀ(M⊗I₃)w
  // plus E stays constant to the integration tolerance over several periods.
  Problem p = box_problem(kBar, {4, 1, 1}, model::MassKind::consistent);
  clamp_xmin(p, kBar, {4, 1, 1});
  p.validate();
  State s = initial_state(p, 0.0);
  for (int v = 0; v < p.num_nodes(); ++v) s.w[3 * v + 2] = 0.05 * p.rest(v, 0) / kBar.x();
  for (int dof : p.dirichlet.dof) s.w[dof] = 0.0;
  ReferenceOptions options;
  options.rtol = 1e-10;
  options.atol = 1e-14;
  options.order = 5;
  ReferenceIntegrator integrator(p, options);
  integrator.initialize(s);
  const double e0 = total_energy(p, s);
  ASSERT_GT(e0, 0.0);
  double worst = 0.0, tip_min = 0.0, tip_max = 0.0;
  const int tip = p.num_nodes() - 1;
  for (int k = 1; k <= 100; ++k) {
    const State sk = integrator.advance_to(0.01 * k);  // 1 s: several periods of the first bending mode
    worst = std::max(worst, std::abs(total_energy(p, sk) - e0) / e0);
    tip_min = std::min(tip_min, sk.x[3 * tip + 2] - p.rest(tip, 2));
    tip_max = std::max(tip_max, sk.x[3 * tip + 2] - p.rest(tip, 2));
  }
  std::printf("[ measured ] relative energy drift %.3e over 1 s (%ld steps, %ld mass solves)\n", worst,
              integrator.stats().steps, integrator.stats().mass_solves);
  EXPECT_LT(worst, 1e-7);
  EXPECT_LT(tip_min, -1e-4);  // it really swung both ways
  EXPECT_GT(tip_max, 1e-4);
}

TEST(ReferenceConsistentMass, BadConfigurationsAreOneLineErrors) {
  auto one_line = [](const std::string& message, const std::string& needle) {
    EXPECT_NE(message.find(needle), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  };
  // Consistent mass switched on after validate() on a problem without ρV per tet (masses given directly).
  Problem no_tet_mass = box_problem(kBar, {1, 1, 1}, model::MassKind::lumped);
  no_tet_mass.density = 0.0;
  no_tet_mass.validate();
  no_tet_mass.mass_kind = model::MassKind::consistent;
  one_line(error_of([&] { ReferenceIntegrator{no_tet_mass}; }), "ρV per tet");

  // ρV per tet from another density than the lumped masses.
  Problem mismatched = box_problem(kBar, {1, 1, 1}, model::MassKind::consistent);
  mismatched.validate();
  mismatched.tet_mass *= 2.0;
  one_line(error_of([&] { ReferenceIntegrator{mismatched}; }), "row sums");

  // A node outside every tet has no mass.
  Problem orphan = box_problem(kBar, {1, 1, 1}, model::MassKind::consistent);
  orphan.rest.conservativeResize(orphan.num_nodes() + 1, 3);
  orphan.rest.row(orphan.num_nodes() - 1) << 1.0, 1.0, 1.0;
  orphan.mass = lumped_masses(orphan.rest, orphan.tets, kDensity);
  orphan.validate();
  one_line(error_of([&] { ReferenceIntegrator{orphan}; }), "mass > 0");

  // A component-wise constraint under a map A ≠ I: the same rule as with lumped masses.
  Problem rotated = box_problem(kBar, {1, 1, 1}, model::MassKind::consistent);
  rotated.dirichlet.add(0, 1u);
  rotated.trajectory = std::make_shared<SpinningFrame>(rotated.num_nodes(), 2.0, Eigen::Vector3d::Zero());
  rotated.validate();
  ReferenceIntegrator integrator(rotated);
  integrator.initialize(initial_state(rotated, 0.0));
  one_line(error_of([&] { integrator.advance_to(0.1); }), "not the identity");
}

}  // namespace
}  // namespace sflsh::fullspace
