// The SUNDIALS reference integrator on hand-built bars: its Jacobian against finite differences, energy
// conservation of a free oscillation, convergence in rtol, exact rigid motions (a translating frame,
// free fall), and clean failures (non-finite forcing, bad input).
#include "total_energy.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

namespace sflsh::fullspace {
namespace {

/// A bar [0, cells·h] × [0, h] × [0, h] of `cells` cubes along x, each cut into 6 tets (Freudenthal), with
/// one homogeneous skin material (normal along z) and lumped masses of the given density.
Problem bar_problem(int cells, double h, double density, double young_tangent = 5000.0, double young_normal = 2000.0) {
  Problem p;
  const int n = 4 * (cells + 1);
  p.rest.resize(n, 3);
  auto node = [](int ix, int iy, int iz) { return 4 * ix + 2 * iy + iz; };
  for (int ix = 0; ix <= cells; ++ix) {
    for (int iy = 0; iy < 2; ++iy) {
      for (int iz = 0; iz < 2; ++iz) p.rest.row(node(ix, iy, iz)) << ix * h, iy * h, iz * h;
    }
  }
  // Kuhn's 6 tets of a cube: the paths 000 → e_a → e_a + e_b → 111 over the permutations (a, b, c).
  const int permutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  p.tets.resize(6 * cells, 4);
  int e = 0;
  for (int ix = 0; ix < cells; ++ix) {
    for (const auto& perm : permutations) {
      std::array<int, 3> corner{0, 0, 0};
      std::array<int, 4> tet{};
      tet[0] = node(ix, 0, 0);
      for (int k = 0; k < 3; ++k) {
        ++corner[static_cast<std::size_t>(perm[k])];
        tet[static_cast<std::size_t>(k + 1)] = node(ix + corner[0], corner[1], corner[2]);
      }
      const Eigen::Vector3d a = p.rest.row(tet[0]), b = p.rest.row(tet[1]), c = p.rest.row(tet[2]),
                            d = p.rest.row(tet[3]);
      if ((b - a).dot((c - a).cross(d - a)) < 0.0) std::swap(tet[2], tet[3]);
      p.tets.row(e++) << tet[0], tet[1], tet[2], tet[3];
    }
  }
  material::SkinMaterial skin;
  skin.young_tangent = young_tangent;
  skin.young_normal = young_normal;
  p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                        material::make_orthotropic_fung(skin, Eigen::Vector3d::UnitZ()));
  p.mass = lumped_masses(p.rest, p.tets, density);
  p.density = density;
  return p;
}

/// The nodes of the bar's x = 0 end (4 nodes).
void clamp_left_end(Problem& p) {
  for (int v = 0; v < 4; ++v) p.dirichlet.add(v, 7u);
}

/// p = A(t) x + d(t) with A(t) = R₀ R_z(ω t) and d(t) = v₀ t + a t²/2 for every node; NaN from t_nan on.
class TestTrajectory : public NodeTrajectory {
 public:
  TestTrajectory(int num_nodes, const Eigen::Matrix3d& rotation, double spin, const Eigen::Vector3d& velocity,
                 const Eigen::Vector3d& acceleration, double t_nan = std::numeric_limits<double>::infinity())
      : n_(num_nodes),
        rotation_(rotation),
        spin_(spin),
        velocity_(velocity),
        acceleration_(acceleration),
        t_nan_(t_nan) {}

  int num_nodes() const override { return n_; }

  void evaluate(double t, NodeFrame& frame, NodeFrame* rate) const override {
    const double nan = t >= t_nan_ ? std::numeric_limits<double>::quiet_NaN() : 0.0;
    const Eigen::Matrix3d spin = Eigen::AngleAxisd(spin_ * t, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    Eigen::Matrix3d spin_rate;
    spin_rate << -std::sin(spin_ * t), -std::cos(spin_ * t), 0.0, std::cos(spin_ * t), -std::sin(spin_ * t), 0.0, 0.0,
        0.0, 0.0;
    const Eigen::Vector3d d = velocity_ * t + 0.5 * t * t * acceleration_ + Eigen::Vector3d::Constant(nan);
    frame.A.assign(static_cast<std::size_t>(n_), rotation_ * spin);
    frame.d = d.transpose().replicate(n_, 1);
    if (rate != nullptr) {
      rate->A.assign(static_cast<std::size_t>(n_), spin_ * rotation_ * spin_rate);
      rate->d = (velocity_ + t * acceleration_).transpose().replicate(n_, 1);
    }
  }

 private:
  int n_;
  Eigen::Matrix3d rotation_;
  double spin_;
  Eigen::Vector3d velocity_, acceleration_;
  double t_nan_;
};

Eigen::Matrix3d some_rotation() {
  return Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
}

using sflsh::testing::total_energy;

TEST(ReferenceIntegrator, JacobianMatchesFiniteDifferences) {
  // A deformed, moving state under a spinning frame with a clamped end, exact Hessian: every block of
  // J = ∂f/∂y (x and w columns, prescribed rows and columns) against central differences of f.
  Problem p = bar_problem(3, 0.02, 1000.0);
  clamp_left_end(p);
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.trajectory = std::make_shared<TestTrajectory>(p.num_nodes(), some_rotation(), 1.3, Eigen::Vector3d(0.1, 0.0, 0.2),
                                                  Eigen::Vector3d(1.0, -2.0, 0.5));
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
  // The prescribed components: zero rows and columns in the x part.
  for (int dof : p.dirichlet.dof) {
    EXPECT_EQ(J.row(dof).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(J.row(nx + dof).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(J.col(dof).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(ReferenceIntegrator, FreeOscillationConservesEnergy) {
  // A bar clamped at one end, no gravity, set swinging by a transverse velocity that grows along the bar.
  // The SDIRK method is not symplectic, but at rtol 1e-8 its energy drift over several periods is tiny.
  Problem p = bar_problem(4, 0.025, 1000.0);
  clamp_left_end(p);
  p.validate();
  State s = initial_state(p, 0.0);
  for (int v = 0; v < p.num_nodes(); ++v) s.w[3 * v + 2] = 0.05 * p.rest(v, 0) / 0.1;  // up to 5 cm/s at the tip
  for (int dof : p.dirichlet.dof) s.w[dof] = 0.0;
  ReferenceOptions options;
  options.rtol = 1e-8;
  options.atol = 1e-12;
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
    for (int dof : p.dirichlet.dof) {
      ASSERT_EQ(sk.x[dof], p.rest(dof / 3, dof % 3));
      ASSERT_EQ(sk.w[dof], 0.0);
    }
  }
  EXPECT_LT(worst, 1e-5);
  EXPECT_LT(tip_min, -1e-4);  // it really swung both ways
  EXPECT_GT(tip_max, 1e-4);
  const ReferenceStats& st = integrator.stats();
  EXPECT_GT(st.steps, 10);
  EXPECT_GE(st.jac_evals, 1);
  EXPECT_GT(st.seconds, 0.0);
  EXPECT_DOUBLE_EQ(integrator.time(), 1.0);
}

TEST(ReferenceIntegrator, ErrorDecreasesWithTolerance) {
  // Bar clamped at one end, driven by a spinning, accelerating frame under gravity: the error against a
  // very tight run falls with rtol.
  Problem p = bar_problem(3, 0.025, 1000.0);
  clamp_left_end(p);
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.trajectory = std::make_shared<TestTrajectory>(p.num_nodes(), Eigen::Matrix3d::Identity(), 2.0,
                                                  Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 1.0, 0.0));
  p.validate();
  auto run = [&](double rtol, int order) {
    ReferenceOptions options;
    options.rtol = rtol;
    options.atol = rtol * 1e-3;
    options.order = order;
    ReferenceIntegrator integrator(p, options);
    integrator.initialize(initial_state(p, 0.0));
    return integrator.advance_to(0.3);
  };
  // The 5th-order table reaches rtol 1e-12 in ~1200 steps; the 4th-order one needs ~17000 there.
  const State exact = run(1e-12, 5);
  double previous = std::numeric_limits<double>::infinity();
  for (double rtol : {1e-4, 1e-6, 1e-8}) {
    // Measured: 2.3e-7, 1.9e-9, 1.3e-11 (order 4, deformation ~0.085 m).
    const double error = (run(rtol, 4).x - exact.x).lpNorm<Eigen::Infinity>();
    EXPECT_LT(error, 0.1 * previous) << "rtol " << rtol;
    EXPECT_LT(error, rtol) << "rtol " << rtol;
    previous = error;
  }
  EXPECT_GT((exact.x - initial_state(p, 0.0).x).lpNorm<Eigen::Infinity>(), 1e-3);  // the bar did deform
}

TEST(ReferenceIntegrator, RigidTranslationFrameReproducesRigidMotion) {
  // p = R₀x + a t²/2 with gravity g = a: in the unposed frame the inertial force of the frame cancels
  // gravity, so nothing deforms, x stays X (one node even prescribed) and the posed body moves rigidly
  // with w = a t.
  Problem p = bar_problem(2, 0.02, 1000.0);
  const Eigen::Vector3d a(0.5, -1.0, 2.0);
  const Eigen::Matrix3d R0 = some_rotation();
  p.trajectory = std::make_shared<TestTrajectory>(p.num_nodes(), R0, 0.0, Eigen::Vector3d::Zero(), a);
  p.gravity = a;
  p.dirichlet.add(0, 7u);
  p.validate();
  ReferenceIntegrator integrator(p);
  integrator.initialize(initial_state(p, 0.0));
  const Eigen::VectorXd X = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  for (double t : {0.1, 0.5, 1.0}) {
    const State s = integrator.advance_to(t);
    EXPECT_LT((s.x - X).lpNorm<Eigen::Infinity>(), 1e-9) << "t = " << t;
    for (int v = 0; v < p.num_nodes(); ++v) {
      EXPECT_LT((s.w.segment<3>(3 * v) - a * t).norm(), 1e-8) << "node " << v << ", t = " << t;
    }
  }
  // Without gravity the posed body stays put (inertia) while x translates rigidly by −R₀ᵀa t²/2.
  Problem q = bar_problem(2, 0.02, 1000.0);
  q.trajectory = p.trajectory;
  q.validate();
  ReferenceIntegrator free_body(q);
  free_body.initialize(initial_state(q, 0.0));
  const State s = free_body.advance_to(1.0);
  for (int v = 0; v < q.num_nodes(); ++v) {
    const Eigen::Vector3d expected = X.segment<3>(3 * v) - R0.transpose() * a * 0.5;
    EXPECT_LT((s.x.segment<3>(3 * v) - expected).norm(), 1e-8) << "node " << v;
    EXPECT_LT(s.w.segment<3>(3 * v).norm(), 1e-8) << "node " << v;
  }
}

TEST(ReferenceIntegrator, FreeFallUnderGravity) {
  Problem p = bar_problem(2, 0.02, 1000.0);
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.validate();
  ReferenceIntegrator integrator(p);
  integrator.initialize(initial_state(p, 0.0));
  const double t = 0.5;
  const State s = integrator.advance_to(t);
  EXPECT_DOUBLE_EQ(s.t, t);
  for (int v = 0; v < p.num_nodes(); ++v) {
    const Eigen::Vector3d expected = p.rest.row(v).transpose() + 0.5 * t * t * p.gravity;
    EXPECT_LT((s.x.segment<3>(3 * v) - expected).norm(), 1e-9) << "node " << v;
    EXPECT_LT((s.w.segment<3>(3 * v) - t * p.gravity).norm(), 1e-9) << "node " << v;
  }
  const Energies e0 = energies(p, initial_state(p, 0.0)), e = energies(p, s);
  EXPECT_NEAR(e.kinetic + e.gravity, e0.kinetic + e0.gravity, 1e-9);
  EXPECT_LT(e.elastic, 1e-12);
}

TEST(ReferenceIntegrator, NonFiniteForcingThrowsQuietly) {
  // The frame turns NaN at t = 0.05: ARKODE keeps cutting the step and finally gives up. The result is
  // one sflsh::Error naming ARKODE's flag, the time reached and the reason, and nothing on stderr.
  Problem p = bar_problem(2, 0.02, 1000.0);
  clamp_left_end(p);
  p.trajectory = std::make_shared<TestTrajectory>(p.num_nodes(), Eigen::Matrix3d::Identity(), 0.0,
                                                  Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 1.0), 0.05);
  p.validate();
  ReferenceIntegrator integrator(p);
  integrator.initialize(initial_state(p, 0.0));
  EXPECT_NO_THROW(integrator.advance_to(0.04));
  ::testing::internal::CaptureStderr();
  std::string message;
  try {
    integrator.advance_to(0.1);
  } catch (const Error& error) {
    message = error.what();
  }
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(message.find("ARKODE gave up"), std::string::npos) << message;
  EXPECT_NE(message.find("ARK_"), std::string::npos) << message;
  EXPECT_NE(message.find("not finite"), std::string::npos) << message;
  EXPECT_TRUE(err.empty()) << err;
  EXPECT_LE(integrator.time(), 0.05 + 1e-12);
  EXPECT_GE(integrator.time(), 0.04);
  // The integrator refuses to go on until re-initialized.
  EXPECT_THROW(integrator.advance_to(0.2), Error);
  integrator.initialize(initial_state(p, 0.0));
  EXPECT_NO_THROW(integrator.advance_to(0.01));
}

TEST(ReferenceIntegrator, RejectsBadInput) {
  Problem massless = bar_problem(1, 0.02, 0.0);
  clamp_left_end(massless);
  massless.validate();
  EXPECT_THROW(ReferenceIntegrator{massless}, Error);  // static problem

  Problem orphan = bar_problem(1, 0.02, 1000.0);
  orphan.rest.conservativeResize(orphan.num_nodes() + 1, 3);
  orphan.rest.row(orphan.num_nodes() - 1) << 1.0, 1.0, 1.0;
  orphan.mass = lumped_masses(orphan.rest, orphan.tets, 1000.0);  // the extra node has no mass
  orphan.validate();
  EXPECT_THROW(ReferenceIntegrator{orphan}, Error);

  Problem p = bar_problem(1, 0.02, 1000.0);
  p.validate();
  ReferenceOptions options;
  options.order = 7;
  EXPECT_THROW((ReferenceIntegrator{p, options}), Error);
  options = ReferenceOptions{};
  options.rtol = -1.0;
  EXPECT_THROW((ReferenceIntegrator{p, options}), Error);

  // Component-wise constraints under a map A ≠ I.
  Problem rotated = bar_problem(1, 0.02, 1000.0);
  rotated.dirichlet.add(0, 1u);
  rotated.trajectory = std::make_shared<TestTrajectory>(rotated.num_nodes(), some_rotation(), 0.0,
                                                        Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  rotated.validate();
  ReferenceIntegrator integrator(rotated);
  integrator.initialize(initial_state(rotated, 0.0));
  try {
    integrator.advance_to(0.1);
    ADD_FAILURE() << "expected sflsh::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("not the identity"), std::string::npos) << error.what();
  }
  EXPECT_THROW(integrator.advance_to(0.2), Error);

  // Too much work.
  options = ReferenceOptions{};
  options.max_steps = 3;
  options.rtol = 1e-10;
  Problem falling = bar_problem(1, 0.02, 1000.0);
  falling.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  falling.dirichlet.add(0, 7u);
  falling.validate();
  ReferenceIntegrator busy(falling, options);
  busy.initialize(initial_state(falling, 0.0));
  try {
    busy.advance_to(1.0);
    ADD_FAILURE() << "expected sflsh::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("too much work"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace sflsh::fullspace
