// Verification problem files (`sflsh verify`): the full TOML contract, one-line errors for typos, bad
// expressions, unknown groups and conflicting constraints, muparser drives against their closed forms,
// and the Problem they build.
#include "error_of.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/verify_problem.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <thread>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::error_of;
using sflsh::testing::scratch_dir;

constexpr double kPi = std::numbers::pi;

/// A 10 cm × 2 cm × 2 cm bar of 4 × 1 × 1 cells, its faces as node groups, in dir/mesh/bar.msh.
void write_small_bar(const fs::path& dir) {
  const MshMesh mesh = box_tet_mesh(Eigen::Vector3d(0.1, 0.02, 0.02), {4, 1, 1});
  fs::create_directories(dir / "mesh");
  write_msh(dir / "mesh" / "bar.msh", mesh.nodes, mesh.tets, mesh.node_groups, MshVersion::v22);
}

// The contract example of verify_problem.hpp on the bar (line numbers matter to the tests below).
const std::string kFull = R"toml(mesh = "mesh/bar.msh"
density = 1000.0
gravity = [0.0, 0.0, -9.81]
[material]
young_tangent = 5000.0
young_normal = 2000.0
poisson = 0.25
saturation = 3.0
normal = [0.0, 0.0, 2.0]
[[fix]]
group = "xmin"
components = "xy"
[[drive]]
group = "xmin"
component = "z"
expression = "0.01*sin(2*pi*2*t)"
[time]
duration = 1.0
step = 0.0010416666666666667
integrator = "reference"
rtol = 1e-7
atol = 1e-10
[record]
group = "xmax"
every = 16
[solver]
hessian = "exact"
)toml";

fs::path write_problem(const fs::path& dir, const std::string& text) {
  const fs::path path = dir / "problem.toml";
  std::ofstream(path) << text;
  return path;
}

/// kFull with `from` replaced by `to` (which must occur).
std::string edited(const std::string& from, const std::string& to) {
  const std::size_t at = kFull.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  std::string text = kFull;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

/// The error of loading `text`; checks that it is one line naming problem.toml.
std::string load_error(const std::string& text) {
  const fs::path dir = scratch_dir();
  write_small_bar(dir);
  const fs::path path = write_problem(dir, text);
  const std::string message = error_of([&] { load_verify_problem(path); });
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  return message;
}

TEST(VerifyProblem, FullExampleParses) {
  const fs::path dir = scratch_dir();
  write_small_bar(dir);
  const VerifyProblem p = load_verify_problem(write_problem(dir, kFull));
  EXPECT_EQ(p.mesh_path, dir / "mesh" / "bar.msh");
  EXPECT_EQ(p.mesh.nodes.rows(), 5 * 2 * 2);
  EXPECT_EQ(p.density, 1000.0);
  EXPECT_EQ(p.gravity, Eigen::Vector3d(0.0, 0.0, -9.81));
  EXPECT_EQ(p.material.young_tangent, 5000.0);
  EXPECT_EQ(p.material.young_normal, 2000.0);
  EXPECT_EQ(p.material.poisson, 0.25);
  EXPECT_EQ(p.material.saturation, 3.0);
  EXPECT_EQ(p.normal, Eigen::Vector3d::UnitZ());
  ASSERT_EQ(p.fixes.size(), 1u);
  EXPECT_EQ(p.fixes[0].group, "xmin");
  EXPECT_EQ(p.fixes[0].mask, 3u);
  ASSERT_EQ(p.drives.size(), 1u);
  EXPECT_EQ(p.drives[0].axis, 2);
  EXPECT_EQ(p.drives[0].expression, "0.01*sin(2*pi*2*t)");
  EXPECT_EQ(p.duration, 1.0);
  EXPECT_EQ(p.step, 0.0010416666666666667);
  EXPECT_EQ(p.integrator, VerifyProblem::Integrator::reference);
  EXPECT_EQ(p.mass, model::MassKind::lumped);
  EXPECT_EQ(p.rtol, 1e-7);
  EXPECT_EQ(p.atol, 1e-10);
  EXPECT_EQ(p.record_group, "xmax");
  EXPECT_EQ(p.record_every, 16);
  EXPECT_EQ(p.projection, material::HessianProjection::kNone);
  const std::vector<int> recorded = record_nodes(p);
  EXPECT_EQ(recorded, p.mesh.node_groups.at("xmax"));
  EXPECT_TRUE(std::is_sorted(recorded.begin(), recorded.end()));

  Problem problem = make_problem(p);
  problem.validate();
  EXPECT_TRUE(problem.dynamic());
  EXPECT_NEAR(problem.mass.sum(), 1000.0 * 0.1 * 0.02 * 0.02, 1e-15);
  EXPECT_EQ(problem.gravity, p.gravity);
  EXPECT_EQ(problem.projection, material::HessianProjection::kNone);
  EXPECT_FALSE(problem.trajectory);
  ASSERT_EQ(problem.tet_material.size(), static_cast<std::size_t>(problem.num_tets()));
  EXPECT_EQ(problem.tet_material[0].normal, Eigen::Vector3d::UnitZ());
  // 4 nodes on xmin, x and y fixed, z driven.
  EXPECT_EQ(problem.dirichlet.dof.size(), 12u);
  ASSERT_EQ(problem.dirichlet.drives.size(), 1u);
  const Eigen::VectorXd u = problem.dirichlet.values(0.1);
  EXPECT_NEAR(u.maxCoeff(), 0.01 * std::sin(2 * kPi * 2 * 0.1), 1e-15);
  EXPECT_EQ(u.minCoeff(), 0.0);
}

TEST(VerifyProblem, MinimalStaticProblemUsesDefaults) {
  const fs::path dir = scratch_dir();
  write_small_bar(dir);
  const VerifyProblem p = load_verify_problem(write_problem(dir, R"(mesh = "mesh/bar.msh"
[material]
young_tangent = 5000
young_normal = 2000
[[fix]]
group = "xmin"
components = "zyx"
[time]
duration = 1
step = 0.5
[record]
group = "xmax"
)"));
  EXPECT_EQ(p.density, 0.0);
  EXPECT_EQ(p.gravity, Eigen::Vector3d::Zero());
  EXPECT_EQ(p.material.poisson, 0.2);
  EXPECT_EQ(p.material.saturation, 4.0);
  EXPECT_EQ(p.fixes[0].mask, 7u);
  EXPECT_EQ(p.integrator, VerifyProblem::Integrator::backward_euler);
  EXPECT_EQ(p.mass, model::MassKind::lumped);
  EXPECT_EQ(p.record_every, 1);
  EXPECT_EQ(p.projection, material::HessianProjection::kStressDerivative);
  Problem problem = make_problem(p);
  problem.validate();
  EXPECT_FALSE(problem.dynamic());
}

TEST(VerifyProblem, UnknownKeysAreNamedWithTheirLine) {
  const std::string top = load_error(edited("density = 1000.0\n", "densty = 1000.0\n"));
  EXPECT_NE(top.find("problem.toml:2: densty: unknown key"), std::string::npos) << top;
  const std::string nested = load_error(edited("saturation = 3.0\n", "saturation = 3.0\nyoung_shear = 1.0\n"));
  EXPECT_NE(nested.find("problem.toml:9: material.young_shear: unknown key"), std::string::npos) << nested;
  const std::string in_fix = load_error(edited("components = \"xy\"\n", "components = \"xy\"\nvalue = 0.0\n"));
  EXPECT_NE(in_fix.find(":13: fix[1].value"), std::string::npos) << in_fix;
}

TEST(VerifyProblem, BadValuesAreOneLineErrors) {
  EXPECT_NE(load_error(edited("step = 0.0010416666666666667", "")).find("time.step: missing"), std::string::npos);
  EXPECT_NE(load_error(edited("step = 0.0010416666666666667", "step = -1.0")).find(":19: time.step: must be > 0"),
            std::string::npos);
  EXPECT_NE(load_error(edited("poisson = 0.25", "poisson = 0.5")).find(":7: material.poisson: must be in (-1, 0.5)"),
            std::string::npos);
  EXPECT_NE(load_error(edited("young_normal = 2000.0", "young_normal = \"soft\""))
                .find("material.young_normal: must be a number"),
            std::string::npos);
  EXPECT_NE(load_error(edited("young_normal = 2000.0\n", "")).find("material.young_normal: missing"),
            std::string::npos);
  EXPECT_NE(load_error(edited("normal = [0.0, 0.0, 2.0]", "normal = [0.0, 0.0, 0.0]")).find("material.normal"),
            std::string::npos);
  EXPECT_NE(load_error(edited("components = \"xy\"", "components = \"xx\"")).find("fix[1].components"),
            std::string::npos);
  EXPECT_NE(load_error(edited("component = \"z\"", "component = \"xz\"")).find("drive[1].component"),
            std::string::npos);
  EXPECT_NE(load_error(edited("integrator = \"reference\"", "integrator = \"rk4\"")).find("rk4"), std::string::npos);
  EXPECT_NE(load_error(edited("hessian = \"exact\"", "hessian = \"approximate\"")).find("solver.hessian"),
            std::string::npos);
  EXPECT_NE(load_error(edited("every = 16", "every = 1.5")).find("record.every"), std::string::npos);
  EXPECT_NE(load_error(edited("[record]\ngroup = \"xmax\"\nevery = 16\n", "")).find("[record]: missing"),
            std::string::npos);
  EXPECT_NE(load_error(edited("mesh/bar.msh", "mesh/none.msh")).find("none.msh"), std::string::npos);
  EXPECT_NE(load_error(edited("density = 1000.0", "density = \"1000")).find("problem.toml:2:"), std::string::npos);
}

TEST(VerifyProblem, MassAndIntegratorSpellings) {
  const fs::path dir = scratch_dir();
  write_small_bar(dir);
  for (const std::string integrator : {"backward_euler", "bdf2", "newmark", "reference"}) {
    for (const std::string mass : {"lumped", "consistent"}) {
      const std::string text = edited("density = 1000.0\n", "density = 1000.0\nmass = \"" + mass + "\"\n");
      const std::size_t at = text.find("integrator = \"reference\"");
      ASSERT_NE(at, std::string::npos);
      const VerifyProblem p = load_verify_problem(
          write_problem(dir, std::string(text).replace(at, 24, "integrator = \"" + integrator + "\"")));
      EXPECT_EQ(to_string(p.integrator), integrator);
      EXPECT_EQ(model::to_string(p.mass), mass);
      Problem problem = make_problem(p);
      problem.validate();
      EXPECT_EQ(problem.mass_kind, p.mass);
      if (p.mass == model::MassKind::consistent) {
        // ρV per tet, whose consistent matrix has the lumped masses as row sums.
        ASSERT_EQ(problem.tet_mass.size(), problem.num_tets());
        const Eigen::VectorXd row_sums = problem.mass_matrix() * Eigen::VectorXd::Ones(problem.num_nodes());
        EXPECT_LT((row_sums - problem.mass).cwiseAbs().maxCoeff(), 1e-15);
      }
    }
  }
}

TEST(VerifyProblem, BadMassOrIntegratorIsAOneLineErrorListingTheChoices) {
  const std::string mass = load_error(edited("density = 1000.0\n", "density = 1000.0\nmass = \"diagonal\"\n"));
  EXPECT_NE(mass.find("problem.toml:3: mass: expected one of \"lumped\", \"consistent\", got \"diagonal\""),
            std::string::npos)
      << mass;
  const std::string integrator = load_error(edited("integrator = \"reference\"", "integrator = \"rk4\""));
  EXPECT_NE(integrator.find("problem.toml:20: time.integrator: expected one of \"backward_euler\", \"bdf2\", "
                            "\"newmark\", \"reference\", got \"rk4\""),
            std::string::npos)
      << integrator;
  const std::string number = load_error(edited("density = 1000.0\n", "density = 1000.0\nmass = 1\n"));
  EXPECT_NE(number.find(":3: mass: must be a string"), std::string::npos) << number;
  // A static problem (no density) has no inertia: consistent mass and the dynamic integrators are refused.
  const std::string static_mass = load_error(edited("density = 1000.0\n", "mass = \"consistent\"\n"));
  EXPECT_NE(static_mass.find(":2: mass: \"consistent\" needs density > 0"), std::string::npos) << static_mass;
  std::string text = edited("density = 1000.0\n", "");
  text.replace(text.find("integrator = \"reference\""), 24, "integrator = \"newmark\"");
  const std::string static_newmark = load_error(text);
  EXPECT_NE(static_newmark.find("time.integrator: \"newmark\" needs a dynamic problem"), std::string::npos)
      << static_newmark;
}

TEST(VerifyProblem, MeshErrorsNameBothFiles) {
  const fs::path dir = scratch_dir();
  fs::create_directories(dir / "mesh");
  std::ofstream(dir / "mesh" / "bar.msh") << "$MeshFormat\n4.1 1 8\n$EndMeshFormat\n";
  const std::string message = error_of([&] { load_verify_problem(write_problem(dir, kFull)); });
  EXPECT_NE(message.find("problem.toml:1: mesh:"), std::string::npos) << message;
  EXPECT_NE(message.find("bar.msh:2:"), std::string::npos) << message;
  EXPECT_NE(message.find("binary"), std::string::npos) << message;
}

TEST(VerifyProblem, BadExpressionsAreErrors) {
  const std::string syntax = load_error(edited("0.01*sin(2*pi*2*t)", "0.01*sin(2*pi*2*t"));
  EXPECT_NE(syntax.find(":16: drive[1].expression"), std::string::npos) << syntax;
  const std::string variable = load_error(edited("0.01*sin(2*pi*2*t)", "0.01*sin(2*pi*2*time)"));
  EXPECT_NE(variable.find("time"), std::string::npos) << variable;
  const std::string nan = load_error(edited("0.01*sin(2*pi*2*t)", "sqrt(t-1)"));
  EXPECT_NE(nan.find("not finite"), std::string::npos) << nan;
  // Plausibility before solving: over [0, time.duration] a drive stays within ten times the mesh's size (the bar's
  // diagonal is 0.104 m, so 1.04 m); 10³⁰⁰·t and 2·t are refused at parse time, 0.5·t is not.
  const std::string huge = load_error(edited("0.01*sin(2*pi*2*t)", "1e300*t"));
  EXPECT_NE(huge.find(":16: drive[1].expression: '1e300*t' = 1e+297 m at t = 0.001 s; expected |u| ≤ 1.04 m"),
            std::string::npos)
      << huge;
  EXPECT_NE(load_error(edited("0.01*sin(2*pi*2*t)", "2*t")).find("expected |u| ≤ 1.04 m over [0, time.duration = 1 s]"),
            std::string::npos);
  EXPECT_NE(load_error(edited("0.01*sin(2*pi*2*t)", "1/(t-0.5)")).find("drive[1].expression"), std::string::npos);
  const fs::path dir = scratch_dir();
  write_small_bar(dir);
  EXPECT_NO_THROW(load_verify_problem(write_problem(dir, edited("0.01*sin(2*pi*2*t)", "0.5*t"))));
  // Non-finite later on: an error naming the expression and t, not a NaN.
  const ScalarDrive drive = expression_drive("1/(t-2)");
  EXPECT_NE(error_of([&] { drive.value(2.0); }).find("'1/(t-2)' is not finite at t = 2"), std::string::npos);
}

TEST(VerifyProblem, UnknownGroupListsTheMeshGroups) {
  const std::string message = load_error(edited("group = \"xmin\"\ncomponent =", "group = \"bone\"\ncomponent ="));
  EXPECT_NE(message.find(":14: drive[1].group: no node group 'bone'"), std::string::npos) << message;
  EXPECT_NE(message.find("'all', 'volume', 'xmax', 'xmin'"), std::string::npos) << message;
}

TEST(VerifyProblem, FixedAndDrivenComponentIsAnErrorButFixingTwiceIsNot) {
  const std::string both = load_error(edited("components = \"xy\"", "components = \"xz\""));
  EXPECT_NE(both.find("drive[1].component"), std::string::npos) << both;
  EXPECT_NE(both.find("fix[1]"), std::string::npos) << both;
  const std::string twice =
      load_error(edited("[time]", "[[drive]]\ngroup = \"ymin\"\ncomponent = \"z\"\nexpression = \"t\"\n[time]"));
  EXPECT_NE(twice.find("drive[2].component"), std::string::npos) << twice;

  const fs::path dir = scratch_dir();
  write_small_bar(dir);
  const VerifyProblem p = load_verify_problem(
      write_problem(dir, edited("[[drive]]", "[[fix]]\ngroup = \"ymin\"\ncomponents = \"yx\"\n[[drive]]")));
  ASSERT_EQ(p.fixes.size(), 2u);
  Problem problem = make_problem(p);
  problem.validate();
  // xmin (4 nodes) x, y, z; ymin (10 nodes) x, y; shared: the 2 nodes on both faces.
  EXPECT_EQ(problem.dirichlet.dof.size(), 12u + 20u - 4u);
}

TEST(VerifyProblem, DriveValuesAndRatesMatchTheirClosedForms) {
  const ScalarDrive drive = expression_drive("0.01*sin(2*pi*2*t)");
  const double w = 2 * kPi * 2;
  for (const double t : {0.0, 0.01, 0.1234, 0.3, 1.0, 7.25, 100.3}) {
    EXPECT_NEAR(drive.value(t), 0.01 * std::sin(w * t), 1e-15) << t;
    // Central differences: relative error ~ (h·ω)²/6 + 1e-16/h against the amplitude 0.01·ω.
    EXPECT_NEAR(drive.rate(t), 0.01 * w * std::cos(w * t), 1e-6 * 0.01 * w) << t;
  }
  const ScalarDrive constants = expression_drive("e*1e-3 + pi*2.5e1 + (t<0.05)");
  EXPECT_NEAR(constants.value(0.0), std::numbers::e * 1e-3 + kPi * 25.0 + 1.0, 1e-12);
  EXPECT_NEAR(constants.value(0.1), std::numbers::e * 1e-3 + kPi * 25.0, 1e-12);
  // Copies share one parser under a mutex: concurrent evaluation is safe and exact.
  const ScalarDrive copy = drive;
  std::vector<std::thread> threads;
  std::vector<int> wrong(4, 0);
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&, k] {
      for (int i = 0; i < 2000; ++i) {
        const double t = 0.001 * (i + k);
        if (std::abs(copy.value(t) - 0.01 * std::sin(w * t)) > 1e-15) {
          ++wrong[static_cast<std::size_t>(k)];
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(wrong, std::vector<int>(4, 0));
}

}  // namespace
}  // namespace sflsh::fullspace
