// The exchange between touching bodies: the interface quasi-Newton update on a model problem, the touching
// clusters, and on two bodies pushing back to back that the order of the bodies in the file does not decide who
// gives way, with the convergence report of summary.json.
#include "scratch_dir.hpp"

#include <sflsh/core/vtk_io.hpp>
#include <sflsh/scene/exchange_accelerator.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

namespace sflsh::scene {
namespace {

// Two bodies pressed together by an overlap d, as 1D springs per vertex: body a, solved against b's surface,
// gives way by c_a (d − x_b) (c = k_contact / (k_contact + k_body): near 1 for a stiff penalty), and b likewise.
// The fixed point x_a = c_a d (1 − c_b) / (1 − c_a c_b) splits d between the two.
struct TwoSprings {
  double c_a = 0.94, c_b = 0.8;
  Eigen::VectorXd d = Eigen::VectorXd::LinSpaced(5, 0.001, 0.02);  // [m] per vertex
  Eigen::VectorXd operator()(const Eigen::VectorXd& x) const {
    const auto n = d.size();
    Eigen::VectorXd y(2 * n);
    y.head(n) = c_a * (d - x.tail(n));
    y.tail(n) = c_b * (d - x.head(n));
    return y;
  }
  Eigen::VectorXd solution() const {
    Eigen::VectorXd x(2 * d.size());
    x.head(d.size()) = c_a * (1.0 - c_b) / (1.0 - c_a * c_b) * d;
    x.tail(d.size()) = c_b * (1.0 - c_a) / (1.0 - c_a * c_b) * d;
    return x;
  }
};

TEST(BodyExchange, QuasiNewtonReachesTheSplitOfALinearExchangeInAFewSteps) {
  const TwoSprings h;
  const Eigen::VectorXd solution = h.solution();
  // Each body alone gives way by almost the whole overlap: the plain exchange alternates and barely contracts
  // (|eigenvalues| = √(c_a c_b) ≈ 0.87), and relaxation by ½ leaves an eigenvalue 1 − ½(1 − 0.87) ≈ 0.93.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(10), relaxed = x;
  ExchangeAccelerator accelerator(0.5);
  for (int k = 0; k < 4; ++k) {
    x = accelerator.next(x, h(x));
    relaxed += 0.5 * (h(relaxed) - relaxed);
  }
  // The map is linear, so once the differences span the (here 2-dimensional, as d is one direction per body)
  // range the least-squares model is exact: rounding only.
  EXPECT_LT((x - solution).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((relaxed - solution).cwiseAbs().maxCoeff(), 1e-4);  // the plain relaxation is far from it
  EXPECT_LT((h(x) - x).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(BodyExchange, TouchingClustersLinkBodiesEitherWay) {
  // Group {0, 2, 3, 5}: 0 touches 3, 5 touches 2 (2 does not see 5), 3 touches 7 (another group: ignored).
  const std::vector<std::size_t> group = {0, 2, 3, 5};
  const std::vector<std::vector<std::size_t>> touches = {{3}, {}, {7}, {2}};
  const auto clusters = touching_clusters(group, touches);
  ASSERT_EQ(clusters.size(), 2U);
  EXPECT_EQ(clusters[0], (std::vector<std::size_t>{0, 3}));
  EXPECT_EQ(clusters[1], (std::vector<std::size_t>{2, 5}));
  EXPECT_TRUE(touching_clusters(group, {{}, {}, {}, {}}).empty());  // alone: no exchange
}

// Back to back, 8 cm apart at rest; the second body walks 10 cm into the first in 0.3 s and stays. Both with the
// paper's backward Euler + lumped masses: the σ ratio below measures how the overlap is shared, and backward Euler
// damps the walking body's own jiggle, which with the default BDF2 adds to its σ (ratio 2.19 against 1.6–1.9).
std::string push_scene(bool pushing_first, const std::string& contact) {
  const std::string standing = R"([[body]]
name = "standing"
motion = "rest"
mesh = "coarse"
handles = 30
integrator = "backward_euler"
mass = "lumped"
)";
  const std::string pushing = R"([[body]]
name = "pushing"
motion = "rest"
mesh = "coarse"
handles = 30
integrator = "backward_euler"
mass = "lumped"
placement = { position = [0.0, 0.0, -0.30], yaw = 180.0 }
approach = [{ t = 0.0, position = [0.0, 0.0, 0.0] }, { t = 0.3, position = [0.0, 0.0, -0.10] }]
)";
  return fmt::format(R"([scene]
fps = 30
frames = 12
[effects]
inertia = true
body_contact = true
[contact]
tolerance = 0.001
body_exchange = true
{}
{}{})",
                     contact, pushing_first ? pushing : standing, pushing_first ? standing : pushing);
}

nlohmann::json run_on_two_threads(const std::filesystem::path& dir, const std::string& text) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "scene.toml") << text;
  SceneRunOptions options;
  options.cache_dir = SFLSH_TEST_CACHE;
  options.out = dir / "out";
  options.threads = 2;
  return run_scene(load_scene(dir / "scene.toml"), options);
}

const nlohmann::json& body(const nlohmann::json& summary, const std::string& name) {
  for (const auto& b : summary["bodies"])
    if (b["name"] == name) return b;
  throw std::runtime_error("no body " + name);
}

TEST(BodyExchange, SwappingTheBodiesInTheFileChangesLessThanTheContactTolerance) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json a = run_on_two_threads(dir / "standing_first", push_scene(false, ""));
  const nlohmann::json b = run_on_two_threads(dir / "pushing_first", push_scene(true, ""));
  // The contact tolerance: the deepest accepted penetration, 1 mm.
  constexpr double kTolerance = 1e-3;
  for (const std::string name : {"standing", "pushing"}) {
    SCOPED_TRACE(name);
    const double sigma_a = body(a, name)["dynamics"]["sigma_max_mm"].get<double>();
    const double sigma_b = body(b, name)["dynamics"]["sigma_max_mm"].get<double>();
    EXPECT_GT(sigma_a, 1.0);  // both layers gave way
    EXPECT_LT(std::abs(sigma_a - sigma_b), 1e3 * kTolerance);
    for (int f : {6, 11}) {
      const std::string file = fmt::format("{}_{:06d}.vtp", name, f);
      const vtk::Points pa = vtk::read_points(dir / "standing_first" / "out" / file);
      const vtk::Points pb = vtk::read_points(dir / "pushing_first" / "out" / file);
      EXPECT_LT((pa - pb).rowwise().norm().maxCoeff(), kTolerance) << file;
    }
  }
  // Like bodies pressed back to back share the overlap: neither takes most of it (the one-pass sweep gave the
  // body solved first about 6× the other's σ).
  const double standing = body(a, "standing")["dynamics"]["sigma_max_mm"].get<double>();
  const double pushing = body(a, "pushing")["dynamics"]["sigma_max_mm"].get<double>();
  EXPECT_LT(std::max(standing, pushing) / std::min(standing, pushing), 2.0);
  for (const nlohmann::json* s : {&a, &b}) {
    const nlohmann::json& e = (*s)["body_exchange"];
    EXPECT_TRUE(e["converged"].get<bool>());
    EXPECT_EQ(e["unconverged_steps"], 0);
    EXPECT_GT(e["contact_steps"].get<long>(), 0);
    EXPECT_GT(e["exchanges_max"].get<int>(), 1);  // the touching steps did exchange
    EXPECT_LE(e["exchanges_max"].get<int>(), e["max_exchanges"].get<int>());
    EXPECT_LE(e["residual_penetration_max_mm"].get<double>(), 1e3 * kTolerance);
    EXPECT_LE(e["surface_residual_max_mm"].get<double>(), e["tolerance_mm"].get<double>());
  }
}

TEST(BodyExchange, ACapOnExchangesIsReportedAsNotConverged) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json s = run_on_two_threads(dir, push_scene(false, "max_exchanges = 1"));
  const nlohmann::json& e = s["body_exchange"];
  EXPECT_EQ(e["max_exchanges"], 1);
  EXPECT_EQ(e["exchanges_max"], 1);
  EXPECT_DOUBLE_EQ(e["exchanges_mean"].get<double>(), 1.0);
  EXPECT_FALSE(e["converged"].get<bool>());
  EXPECT_GT(e["unconverged_steps"].get<long>(), 0);
  ASSERT_FALSE(e["per_step"].empty());
  long unconverged = 0;
  for (const auto& step : e["per_step"]) {
    EXPECT_EQ(step["bodies"], nlohmann::json::array({"standing", "pushing"}));
    EXPECT_GE(step["residual_penetration_mm"].get<double>(), 0.0);
    if (!step["converged"].get<bool>()) {
      ++unconverged;
      EXPECT_GT(step["surface_residual_mm"].get<double>(), e["tolerance_mm"].get<double>());
    }
  }
  EXPECT_EQ(unconverged, e["unconverged_steps"].get<long>());
}

}  // namespace
}  // namespace sflsh::scene
