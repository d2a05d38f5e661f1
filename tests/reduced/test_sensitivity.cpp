// Forward sensitivities of the reduced model with respect to the Young moduli: the stress derivative and the
// element force derivative against central differences, the control → tet map against the material fields,
// the cross-time mass against a node-by-node sum, whole trajectories against finite differences of complete
// simulations (box and body layer), and the failures that must be reported rather than returned.
#include "error_of.hpp"
#include "open_body.hpp"
#include "reduced_fixtures.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/reduced/dynamics_sensitivity.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_sensitivity.hpp>
#include <sflsh/reduced/young_derivative.hpp>
#include <sflsh/reduced/young_map.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace sflsh::reduced {
namespace {

// ---------------------------------------------------------------------------------------------------------
// The stress derivative at one point.

material::OrthotropicFung fung(double young_tangent, double young_normal, material::FungScale scale,
                               const Eigen::Vector3d& n) {
  material::SkinMaterial m = testing::skin(young_tangent, young_normal);
  m.fung_scale = scale;
  return material::make_orthotropic_fung(m, n);
}

struct Regime {
  const char* name;
  double stretch;  ///< scale of the diagonal of F
  double shear;    ///< random off-diagonal amplitude
};

class YoungStressFd : public ::testing::TestWithParam<std::tuple<Regime, material::FungScale>> {};

TEST_P(YoungStressFd, AnalyticMatchesCentralDifferences) {
  const auto [regime, scale] = GetParam();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::Matrix3d F = regime.stretch * Eigen::Matrix3d::Identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F(i, j) += regime.shear * u(rng);
    const double yt = 5000.0 * (1.0 + 0.5 * u(rng)), yn = 2000.0 * (1.0 + 0.5 * u(rng));
    const material::OrthotropicFung m = fung(yt, yn, scale, n);
    EXPECT_NEAR(young_moduli(m)[0], yt, 1e-11 * yt);  // P_Y^4 round trip: a few ulps
    EXPECT_NEAR(young_moduli(m)[1], yn, 1e-11 * yn);
    const YoungStressDerivative d = d2psi_ortho_fung_dF_dyoung(F, m);
    // Central differences with a relative step of 1e-5: truncation (δ²/6)·∂³P/∂Y³ is ~1e-11 relative for
    // these smooth (power and exponential) dependences, round-off ~1e-16/1e-5 = 1e-11 relative; 1e-6 leaves
    // five orders of margin while any wrong term (a missing ∂c or ∂P_Y factor) is O(1).
    const double eps = 1e-5;
    const Eigen::Matrix3d fd_t = (material::dpsi_ortho_fung_dF(F, fung(yt * (1 + eps), yn, scale, n)) -
                                  material::dpsi_ortho_fung_dF(F, fung(yt * (1 - eps), yn, scale, n))) /
                                 (2 * eps * yt);
    const Eigen::Matrix3d fd_n = (material::dpsi_ortho_fung_dF(F, fung(yt, yn * (1 + eps), scale, n)) -
                                  material::dpsi_ortho_fung_dF(F, fung(yt, yn * (1 - eps), scale, n))) /
                                 (2 * eps * yn);
    ASSERT_GT(fd_t.norm(), 0.0);
    ASSERT_GT(fd_n.norm(), 0.0);
    EXPECT_LE((d.tangent - fd_t).norm(), 1e-6 * fd_t.norm()) << regime.name << " trial " << trial;
    EXPECT_LE((d.normal - fd_n).norm(), 1e-6 * fd_n.norm()) << regime.name << " trial " << trial;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Regimes, YoungStressFd,
    ::testing::Combine(::testing::Values(Regime{"stretch", 1.2, 0.1}, Regime{"compression", 0.8, 0.1},
                                         Regime{"near_inversion", 0.2, 0.05}, Regime{"large_shear", 1.0, 0.4}),
                       ::testing::Values(material::FungScale::kTangentOverSaturation,
                                         material::FungScale::kTangentTimesSaturation, material::FungScale::kNone)),
    [](const ::testing::TestParamInfo<YoungStressFd::ParamType>& param) {
      const material::FungScale scale = std::get<1>(param.param);
      return std::string(std::get<0>(param.param).name) + (scale == material::FungScale::kNone ? "_no_fung"
                                                           : scale == material::FungScale::kTangentTimesSaturation
                                                               ? "_c_times_s"
                                                               : "_c_over_s");
    });

// ---------------------------------------------------------------------------------------------------------
using testing::all_tets;
using testing::box_young_map;
using testing::set_box_young;

Eigen::MatrixX2d box_control_young() {
  Eigen::MatrixX2d young(2, 2);
  young << 4000.0, 1500.0, 9000.0, 3500.0;
  return young;
}

using testing::shake;

TEST(YoungSensitivity, ElementForceDerivativeMatchesCentralDifferences) {
  auto c = testing::box_case({4, 4, 3});
  set_box_young(c.problem, box_control_young());
  const Subspace s = testing::box_subspace(c);
  CubatureOptions co;
  co.count = 40;
  const Cubature cub = select_cubature(c.problem, s, co);
  SensitivityIntegrator integrator(c.problem, s, cub, box_young_map(c.problem, cub.tets));
  CubatureElastic elastic(c.problem, s, cub);  // reads the problem's materials at every evaluation
  for (double amplitude : {1e-3, 1e-2}) {
    const Eigen::VectorXd q = testing::random_q(s.num_dofs(), amplitude, 11);
    const Eigen::MatrixXd analytic = integrator.elastic_gradient_dyoung(q);
    for (int column = 0; column < 4; ++column) {
      const int control = column % 2, modulus = column / 2;
      const Eigen::MatrixX2d base = box_control_young();
      const double delta = 1e-5 * base(control, modulus);
      Eigen::VectorXd g_plus = Eigen::VectorXd::Zero(s.num_dofs()), g_minus = g_plus;
      Eigen::MatrixX2d y = base;
      y(control, modulus) += delta;
      set_box_young(c.problem, y);
      elastic.add_gradient(q, g_plus);
      y(control, modulus) -= 2 * delta;
      set_box_young(c.problem, y);
      elastic.add_gradient(q, g_minus);
      set_box_young(c.problem, base);
      const Eigen::VectorXd fd = (g_plus - g_minus) / (2 * delta);
      // Same budget as the point test (relative step 1e-5: truncation and round-off ~1e-11 relative); the
      // sum over cubature points is linear, so it adds nothing but the round-off of the sum.
      ASSERT_GT(fd.norm(), 0.0);
      EXPECT_LE((analytic.col(column) - fd).norm(), 1e-6 * fd.norm())
          << "column " << column << ", amplitude " << amplitude;
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// The cross-time mass.

using sflsh::testing::open_body;

model::BodyLayerOptions coarse_layer_options() {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  return options;
}

TEST(YoungSensitivity, CrossMassMatchesTheNodeByNodeSum) {
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 30);
  const model::BodyLayer layer =
      model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, coarse_layer_options());
  ReducedModelOptions ro;
  ro.point_handles = 12;
  ro.cache_dir = SFLSH_TEST_CACHE;
  const ReducedModel model = build_reduced_model(layer, ro);
  ReducedInertia inertia(layer.problem, model.subspace);
  const double t1 = 0.25, t0 = 0.2, h = t1 - t0;
  const Eigen::VectorXd x_rest = Eigen::Map<const Eigen::VectorXd>(layer.problem.rest.data(), layer.problem.num_dofs());
  inertia.set_time(t1, x_rest);
  Eigen::MatrixXd cross, same, hessian;
  inertia.cross_mass(t0, cross);
  inertia.cross_mass(t1, same);
  inertia.mass_hessian(h, hessian);
  // Node by node: Σ_i m_i b_is b_ir A_i(t1)ᵀ A_i(t0).
  const std::vector<int> active = model.subspace.active_nodes();
  model::NodeFrame f1, f0;
  layer.problem.trajectory->evaluate_nodes(t1, active, f1);
  layer.problem.trajectory->evaluate_nodes(t0, active, f0);
  Eigen::MatrixXd direct = Eigen::MatrixXd::Zero(model.subspace.num_dofs(), model.subspace.num_dofs());
  for (std::size_t a = 0; a < active.size(); ++a) {
    const Eigen::Matrix3d G = layer.problem.mass[active[a]] * (f1.A[a].transpose() * f0.A[a]);
    for (SparseRowMatrix::InnerIterator si(model.subspace.basis, active[a]); si; ++si)
      for (SparseRowMatrix::InnerIterator ri(model.subspace.basis, active[a]); ri; ++ri)
        direct.block<3, 3>(3 * si.col(), 3 * ri.col()) += si.value() * ri.value() * G;
  }
  // Two summation orders of the same ~1e4 products: round-off ~1e-14 of the largest entry.
  ASSERT_GT(direct.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((cross - direct).cwiseAbs().maxCoeff(), 1e-12 * direct.cwiseAbs().maxCoeff());
  EXPECT_LE((same / (h * h) - hessian).cwiseAbs().maxCoeff(), 1e-12 * hessian.cwiseAbs().maxCoeff());
  // Over a twentieth of a second of hip shaking the bones turn: M(t1, t0) is not M(t1, t1).
  EXPECT_GT((cross - same).cwiseAbs().maxCoeff(), 1e-6 * same.cwiseAbs().maxCoeff());
}

// ---------------------------------------------------------------------------------------------------------
// The control → tet map.

TEST(YoungMap, MatchesTheLayerMaterialFieldsOnRandomKappa) {
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 4);
  const model::BodyLayer layer =
      model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, coarse_layer_options());
  const LayerYoungMap map(layer);
  ASSERT_EQ(map.num_controls(), 6);
  const std::vector<int> tets = all_tets(layer.problem);
  const Eigen::MatrixXd W = map.tet_map(tets);
  // The built problem's materials (default κ) are W · Y_control (read back from P_Y: a few ulps).
  const Eigen::MatrixX2d built = W * map.control_young();
  double worst = 0.0;
  for (int e = 0; e < layer.problem.num_tets(); ++e) {
    const Eigen::Vector2d y = young_moduli(layer.problem.tet_material[static_cast<std::size_t>(e)]);
    worst = std::max(worst, ((y - built.row(e).transpose()).array() / y.array()).abs().maxCoeff());
  }
  EXPECT_LE(worst, 1e-12);
  // Random κ within the bounds: the fields are linear in κ for fixed geometry, so W reproduces them up to the
  // round-off of two evaluation orders of the same linear map (~1e-15 relative).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> log_young(std::log(500.0), std::log(50000.0));
  for (int trial = 0; trial < 3; ++trial) {
    material::KappaMatrix kappa = layer.material.kappa();
    Eigen::MatrixX2d young(kappa.rows(), 2);
    for (Eigen::Index i = 0; i < kappa.rows(); ++i) {
      young(i, 0) = kappa(i, material::kYoungTangent) = std::exp(log_young(rng));
      young(i, 1) = kappa(i, material::kYoungNormal) = std::exp(log_young(rng));
    }
    const material::LayerMaterialFields fields =
        material::layer_material_fields(map.retargeter(), map.basis(), kappa, layer.layer.nodes);
    const Eigen::MatrixX2d mapped = W * young;
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd reference = fields.tet.col(1 + k);
      EXPECT_LE(((mapped.col(k) - reference).array() / reference.array()).abs().maxCoeff(), 1e-12) << "trial " << trial;
    }
  }
  // The stiffness scale multiplies W.
  const LayerYoungMap scaled(layer, 2.5);
  EXPECT_LE((scaled.tet_map({0, 7, 19}) - 2.5 * map.tet_map({0, 7, 19})).cwiseAbs().maxCoeff(),
            1e-15 * W.cwiseAbs().maxCoeff() * 2.5);
}

// ---------------------------------------------------------------------------------------------------------
// Whole trajectories against finite differences of complete simulations.

/// The relative disagreement over a trajectory: max_f ‖a_f − b_f‖ / max_f ‖b_f‖ for one column.
double trajectory_error(const std::vector<Eigen::MatrixXd>& analytic, int column,
                        const std::vector<Eigen::VectorXd>& fd) {
  double error = 0.0, scale = 0.0;
  for (std::size_t f = 0; f < fd.size(); ++f) {
    error = std::max(error, (analytic[f].col(column) - fd[f]).norm());
    scale = std::max(scale, fd[f].norm());
  }
  return scale > 0.0 ? error / scale : std::numeric_limits<double>::infinity();
}

std::vector<Eigen::VectorXd> plain_run(const model::Problem& p, const Subspace& s, const Cubature& cub,
                                       const model::State& start, double h, int frames) {
  ReducedSolver integrator(p, s, cub, sensitivity_solver_options());
  integrator.initialize(start);
  std::vector<Eigen::VectorXd> q{integrator.q()};
  for (int f = 0; f < frames; ++f) {
    integrator.step(h);
    q.push_back(integrator.q());
  }
  return q;
}

std::vector<Eigen::VectorXd> central_difference(const std::vector<Eigen::VectorXd>& plus,
                                                const std::vector<Eigen::VectorXd>& minus, double delta) {
  std::vector<Eigen::VectorXd> out;
  for (std::size_t f = 0; f < plus.size(); ++f) out.push_back((plus[f] - minus[f]) / (2 * delta));
  return out;
}

// Budget of both trajectory checks (relative to the largest ‖dq/dY‖ over the run):
// - truncation of the central difference with a relative step of 1e-4: (δ/Y)²/6 · (Y² ∂³q/∂Y³ / ∂q/∂Y) ~ 1e-9;
// - solver tolerance: Newton stops at ‖Δq‖ ≤ 1e-12 m or ‖∇Φ‖ ≤ 1e-12 ‖∇Φ₀‖ (sensitivity_solver_options),
//   an error of ≲ 1e-13 m per state against a difference q(Y+δ) − q(Y−δ) of ≳ 1e-8 m (measured |dq/dY|·2δ
//   on the box): ≲ 1e-5 in the worst case, ~1e-8 measured on both cases;
// - both accumulate over the 20 steps but backward Euler damps, so the errors do not grow geometrically.
// A missing history term (the prediction's dependence on q_{n−1}) is an O(1) disagreement, and treating the
// posed maps as constant over a step (M(t_{n+1}, t_n) ≈ M(t_{n+1}, t_{n+1})) a 1e-2 one on the body layer.
constexpr double kTrajectoryTolerance = 1e-5;

TEST(YoungSensitivity, BoxTrajectoryMatchesFiniteDifferencesOfCompleteSimulations) {
  const model::ScalarDrive drive = shake(0.006, 4.0);
  auto c = testing::box_case({4, 4, 3}, 1000.0, &drive);
  const Eigen::MatrixX2d base = box_control_young();
  set_box_young(c.problem, base);
  const Subspace s = testing::box_subspace(c);
  const Cubature cub = exact_cubature(c.problem.num_tets());
  const model::State start = model::initial_state(c.problem, 0.0);
  const double h = 1.0 / 60.0;
  const int frames = 20;
  const SensitivityResult result =
      simulate_with_sensitivities(c.problem, s, cub, box_young_map(c.problem, cub.tets), start, h, frames);
  ASSERT_EQ(result.dq_dyoung.size(), static_cast<std::size_t>(frames + 1));
  EXPECT_EQ(result.dq_dyoung[0].cwiseAbs().maxCoeff(), 0.0);  // the initial state does not depend on Y
  for (int column = 0; column < 4; ++column) {
    const int control = column % 2, modulus = column / 2;
    const double delta = 1e-4 * base(control, modulus);
    Eigen::MatrixX2d y = base;
    y(control, modulus) += delta;
    set_box_young(c.problem, y);
    const auto plus = plain_run(c.problem, s, cub, start, h, frames);
    y(control, modulus) -= 2 * delta;
    set_box_young(c.problem, y);
    const auto minus = plain_run(c.problem, s, cub, start, h, frames);
    set_box_young(c.problem, base);
    const auto fd = central_difference(plus, minus, delta);
    EXPECT_GT(fd.back().norm(), 0.0);
    EXPECT_LE(trajectory_error(result.dq_dyoung, column, fd), kTrajectoryTolerance) << "column " << column;
  }
}

// The consistent mass: M(t, t') couples the active nodes of neighbouring tets, the attached neighbours' targets
// stay independent of Y (budget as above).
TEST(YoungSensitivity, ConsistentMassTrajectoryMatchesFiniteDifferences) {
  const model::ScalarDrive drive = shake(0.006, 4.0);
  auto c = testing::box_case({4, 4, 3}, 1000.0, &drive);
  c.problem.mass_kind = model::MassKind::consistent;
  c.problem.validate();
  const Eigen::MatrixX2d base = box_control_young();
  set_box_young(c.problem, base);
  const Subspace s = testing::box_subspace(c);
  const Cubature cub = exact_cubature(c.problem.num_tets());
  const model::State start = model::initial_state(c.problem, 0.0);
  const double h = 1.0 / 60.0;
  const int frames = 20;
  const SensitivityResult result =
      simulate_with_sensitivities(c.problem, s, cub, box_young_map(c.problem, cub.tets), start, h, frames);
  for (int column : {0, 3}) {
    const int control = column % 2, modulus = column / 2;
    const double delta = 1e-4 * base(control, modulus);
    Eigen::MatrixX2d y = base;
    y(control, modulus) += delta;
    set_box_young(c.problem, y);
    const auto plus = plain_run(c.problem, s, cub, start, h, frames);
    y(control, modulus) -= 2 * delta;
    set_box_young(c.problem, y);
    const auto minus = plain_run(c.problem, s, cub, start, h, frames);
    set_box_young(c.problem, base);
    const auto fd = central_difference(plus, minus, delta);
    EXPECT_GT(fd.back().norm(), 0.0);
    EXPECT_LE(trajectory_error(result.dq_dyoung, column, fd), kTrajectoryTolerance) << "column " << column;
  }
}

// Steps of changing size (as substeps make them): the prediction's velocity w_n = (p_n − p_{n−1})/h_prev then
// enters with r = h/h_prev ≠ 1.
TEST(YoungSensitivity, VariableStepTrajectoryMatchesFiniteDifferences) {
  const model::ScalarDrive drive = shake(0.006, 4.0);
  auto c = testing::box_case({4, 4, 3}, 1000.0, &drive);
  const Eigen::MatrixX2d base = box_control_young();
  set_box_young(c.problem, base);
  const Subspace s = testing::box_subspace(c);
  const Cubature cub = exact_cubature(c.problem.num_tets());
  const model::State start = model::initial_state(c.problem, 0.0);
  const std::vector<double> steps{1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 40, 1.0 / 90,
                                  1.0 / 60, 1.0 / 30,  1.0 / 240, 1.0 / 60, 1.0 / 60};
  SensitivityIntegrator integrator(c.problem, s, cub, box_young_map(c.problem, cub.tets));
  integrator.initialize(start);
  std::vector<Eigen::MatrixXd> analytic{integrator.dq_dyoung()};
  for (double h : steps) {
    integrator.step(h);
    analytic.push_back(integrator.dq_dyoung());
  }
  const auto run = [&](const Eigen::MatrixX2d& young) {
    set_box_young(c.problem, young);
    ReducedSolver plain(c.problem, s, cub, sensitivity_solver_options());
    plain.initialize(start);
    std::vector<Eigen::VectorXd> q{plain.q()};
    for (double h : steps) {
      plain.step(h);
      q.push_back(plain.q());
    }
    set_box_young(c.problem, base);
    return q;
  };
  for (int column : {0, 3}) {
    const int control = column % 2, modulus = column / 2;
    const double delta = 1e-4 * base(control, modulus);
    Eigen::MatrixX2d plus = base, minus = base;
    plus(control, modulus) += delta;
    minus(control, modulus) -= delta;
    const auto fd = central_difference(run(plus), run(minus), delta);
    EXPECT_LE(trajectory_error(analytic, column, fd), kTrajectoryTolerance) << "column " << column;  // budget as above
  }
}

TEST(YoungSensitivity, BodyLayerTrajectoryMatchesFiniteDifferencesOfCompleteSimulations) {
  const int frames = 20;
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, frames + 2);
  const model::BodyLayer layer =
      model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, coarse_layer_options());
  ReducedModelOptions ro;
  ro.cache_dir = SFLSH_TEST_CACHE;
  const ReducedModel model = build_reduced_model(layer, ro);
  const LayerYoungMap map(layer);
  const model::State start = model::initial_state(layer.problem, 0.0);
  const double h = 1.0 / 60.0;
  const SensitivityResult result = simulate_with_sensitivities(layer.problem, model.subspace, model.cubature,
                                                               map.tet_map(model.cubature.tets), start, h, frames);
  const int N = map.num_controls();
  const Eigen::MatrixX2d base = map.control_young();
  model::Problem perturbed = layer.problem;
  // σ_n, σ_t of the region skin (the fit's measurement) and their derivatives through the skin map.
  const SkinDisplacementMap skin(layer, model.subspace);
  const meshing::RowMatrixX3d all_normals = model::vertex_normals(layer.shaped, open_body().faces);
  meshing::RowMatrixX3d normals(layer.mesh->region_surface.num_vertices(), 3);
  for (Eigen::Index r = 0; r < normals.rows(); ++r)
    normals.row(r) = all_normals.row(layer.mesh->region_surface.vertices[static_cast<std::size_t>(r)]);
  DynamicsAmplitudeSensitivity dynamics(normals, 2 * N);
  for (std::size_t f = 0; f < result.q.size(); ++f)
    dynamics.add(skin.displacement(result.q[f], result.t[f]), skin.derivative(result.dq_dyoung[f]));
  const auto sigma_of = [&](const std::vector<Eigen::VectorXd>& q) {
    model::DynamicsAmplitude amplitude(normals);
    for (std::size_t f = 0; f < q.size(); ++f) amplitude.add(skin.displacement(q[f], result.t[f]));
    Eigen::VectorXd sigma(2 * normals.rows());
    sigma << amplitude.sigma_normal(), amplitude.sigma_tangent();
    return sigma;
  };
  {
    model::DynamicsAmplitude amplitude(normals);
    for (std::size_t f = 0; f < result.q.size(); ++f) amplitude.add(skin.displacement(result.q[f], result.t[f]));
    EXPECT_LE((amplitude.sigma_normal() - dynamics.sigma_normal()).cwiseAbs().maxCoeff(), 1e-12);  // same sums [m]
    EXPECT_LE((amplitude.sigma_tangent() - dynamics.sigma_tangent()).cwiseAbs().maxCoeff(), 1e-12);
  }
  Eigen::MatrixXd dsigma(2 * normals.rows(), 2 * N);
  dsigma << dynamics.sigma_normal_derivative(), dynamics.sigma_tangent_derivative();
  {  // The reduced form of add() (the fit's: du never formed) sums the same terms in another order.
    DynamicsAmplitudeSensitivity reduced_sums(normals, 2 * N);
    for (std::size_t f = 0; f < result.q.size(); ++f) {
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dq = result.dq_dyoung[f];
      reduced_sums.add(skin.displacement(result.q[f], result.t[f]), skin.skin_basis(), dq);
    }
    Eigen::MatrixXd reduced_dsigma(2 * normals.rows(), 2 * N);
    reduced_dsigma << reduced_sums.sigma_normal_derivative(), reduced_sums.sigma_tangent_derivative();
    EXPECT_LE((reduced_dsigma - dsigma).norm(), 1e-12 * dsigma.norm());
    EXPECT_LE((reduced_sums.sigma_tangent() - dynamics.sigma_tangent()).cwiseAbs().maxCoeff(), 1e-15);
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dq = result.dq_dyoung.back();
    EXPECT_THROW(dynamics.add(skin.displacement(result.q.back(), result.t.back()), skin.skin_basis(), dq), Error);
  }
  // Y_t of control 0 and Y_n of control 3 (torso and limb sites of the 6-point material).
  for (const auto& [control, modulus] : {std::pair{0, 0}, std::pair{3, 1}}) {
    const double delta = 1e-4 * base(control, modulus);
    Eigen::MatrixX2d y = base;
    y(control, modulus) += delta;
    map.set_control_young(y, perturbed);
    const auto plus = plain_run(perturbed, model.subspace, model.cubature, start, h, frames);
    y(control, modulus) -= 2 * delta;
    map.set_control_young(y, perturbed);
    const auto minus = plain_run(perturbed, model.subspace, model.cubature, start, h, frames);
    const auto fd = central_difference(plus, minus, delta);
    EXPECT_GT(fd.back().norm(), 0.0);
    EXPECT_LE(trajectory_error(result.dq_dyoung, modulus * N + control, fd), kTrajectoryTolerance)
        << "control " << control << ", modulus " << modulus;
    // σ is a smooth function of the trajectory where σ > 0: the same budget, over all vertices at once.
    const Eigen::VectorXd sigma_fd = (sigma_of(plus) - sigma_of(minus)) / (2 * delta);
    ASSERT_GT(sigma_fd.norm(), 0.0);
    EXPECT_LE((dsigma.col(modulus * N + control) - sigma_fd).norm(), kTrajectoryTolerance * sigma_fd.norm())
        << "control " << control << ", modulus " << modulus;
  }
  // The skin map: du/dY = (K B ⊗ I₃) dq/dY, and u itself is BodyLayer::surface_displacement.
  const Eigen::MatrixXd du = skin.derivative(result.dq_dyoung.back());
  const double eps = 1e-3;  // u is linear in q: any step gives the exact derivative up to round-off
  const Eigen::VectorXd dq = result.dq_dyoung.back().col(0);
  const meshing::RowMatrixX3d u0 = skin.displacement(result.q.back(), result.t.back());
  const meshing::RowMatrixX3d u1 = skin.displacement(result.q.back() + eps * dq / dq.norm(), result.t.back());
  const meshing::RowMatrixX3d diff = (u1 - u0) / eps * dq.norm();
  const Eigen::Map<const Eigen::VectorXd> expected(diff.data(), diff.size());
  EXPECT_LE((du.col(0) - expected).norm(), 1e-9 * expected.norm());
}

// ---------------------------------------------------------------------------------------------------------
// Failures.

TEST(YoungSensitivity, AnIndefiniteOrNonFiniteSystemIsReportedNotSolved) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Identity(3, 3);
  H(2, 2) = -1.0;
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Ones(3, 2);
  EXPECT_NE(sflsh::testing::error_of([&] { solve_step_sensitivity(H, rhs, 0.5); }).find("not positive definite"),
            std::string::npos);
  H(2, 2) = 0.0;  // singular: no strict minimum either
  EXPECT_NE(sflsh::testing::error_of([&] { solve_step_sensitivity(H, rhs, 0.5); }).find("not positive definite"),
            std::string::npos);
  H(2, 2) = 1.0;
  Eigen::MatrixXd bad = rhs;
  bad(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(sflsh::testing::error_of([&] { solve_step_sensitivity(H, bad, 0.5); }).find("non-finite"),
            std::string::npos);
  EXPECT_EQ(solve_step_sensitivity(H, rhs, 0.5), rhs);
}

TEST(YoungSensitivity, ABadMapOrAMissingInitializationIsRefused) {
  const model::ScalarDrive drive = shake(0.006, 4.0);
  auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
  const Subspace s = testing::box_subspace(c);
  const Cubature cub = exact_cubature(c.problem.num_tets());
  const Eigen::MatrixXd W = box_young_map(c.problem, cub.tets);
  EXPECT_NE(sflsh::testing::error_of([&] { SensitivityIntegrator(c.problem, s, cub, W.topRows(3)); }).find("rows"),
            std::string::npos);
  Eigen::MatrixXd nan_map = W;
  nan_map(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(sflsh::testing::error_of([&] { SensitivityIntegrator(c.problem, s, cub, nan_map); }).find("finite"),
            std::string::npos);
  SensitivityIntegrator integrator(c.problem, s, cub, W);
  EXPECT_NE(sflsh::testing::error_of([&] { integrator.step(1.0 / 60.0); }).find("initialize"), std::string::npos);
  integrator.initialize(model::initial_state(c.problem, 0.0));
  EXPECT_EQ(integrator.dq_dyoung().cwiseAbs().maxCoeff(), 0.0);
  integrator.step(1.0 / 60.0);
  EXPECT_TRUE(integrator.dq_dyoung().allFinite());
  EXPECT_GT(integrator.dq_dyoung().cwiseAbs().maxCoeff(), 0.0);
}

// The plain integrator with substep recording is the plain integrator (same trajectory to the bit).
TEST(YoungSensitivity, RecordingSubstepsDoesNotChangeTheTrajectory) {
  const model::ScalarDrive drive = shake(0.006, 4.0);
  auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
  const Subspace s = testing::box_subspace(c);
  const Cubature cub = exact_cubature(c.problem.num_tets());
  ReducedOptions with = sensitivity_solver_options(), without = with;
  without.record_substeps = false;
  ReducedSolver a(c.problem, s, cub, with), b(c.problem, s, cub, without);
  a.initialize(model::initial_state(c.problem, 0.0));
  b.initialize(model::initial_state(c.problem, 0.0));
  for (int k = 0; k < 10; ++k) {
    a.step(1.0 / 60.0);
    b.step(1.0 / 60.0);
    ASSERT_EQ(a.last_substeps().size(), 1u);
    EXPECT_EQ(a.last_substeps().back().q, a.q());
    EXPECT_TRUE(b.last_substeps().empty());
  }
  EXPECT_EQ(a.q(), b.q());
}

}  // namespace
}  // namespace sflsh::reduced
