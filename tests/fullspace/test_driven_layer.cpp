// A driven layer block, the canonical soft-tissue case for the consistent mass: a 10 × 10 × 3 cm slab of our
// skin material (Y_t = 5 kPa, Y_n = 2 kPa, normal z, ρ = 1000 kg/m³) whose bottom face is carried like a bone by
// a smooth sideways bump (2 mm along x over 0.1 s, C¹), then held, so the slab rings freely. Read through
// `sflsh verify`'s problem file (mass = "consistent"), run by
//   - the SUNDIALS reference with the consistent mass (error-controlled: the "exact" dynamics of the mesh),
//   - the same with lumped masses (lumping lowers the frequencies: a phase drift — why consistent mass exists),
//   - Newmark + consistent mass on the model's incremental potential (terms_stepper.hpp, serial Newton),
//   - Newmark + consistent mass in the full-space solver (PETSc), once it honours options.integrator and
//     problem.mass_kind (skipped before: a probe finds it still running backward Euler with lumped masses).
// Differences are the largest over the top face's nodes and the samples, relative to the largest top-face motion.
#include "scratch_dir.hpp"
#include "terms_stepper.hpp"

#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/fullspace/verify_problem.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;

constexpr double kDuration = 0.4;  // [s]: the bump (0.1 s) and ~2 periods of the slab's first shear mode
constexpr double kSample = 0.005;  // [s] between compared samples
constexpr int kSamples = 80;       // kDuration / kSample

/// The block's mesh and problem file in a scratch folder; returns the TOML path.
fs::path write_block(const std::string& mass, const std::string& integrator) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const MshMesh mesh = box_tet_mesh(Eigen::Vector3d(0.1, 0.1, 0.03), {5, 5, 2});
  write_msh(dir / "block.msh", mesh.nodes, mesh.tets, mesh.node_groups);
  const fs::path toml = dir / "block.toml";
  std::ofstream(toml) << "mesh = \"block.msh\"\ndensity = 1000.0\nmass = \"" << mass << R"("
[material]
young_tangent = 5000.0
young_normal = 2000.0
normal = [0.0, 0.0, 1.0]
[[fix]]
group = "zmin"
components = "yz"
[[drive]]
group = "zmin"
component = "x"
expression = "0.002*(t<0.1)*sin(pi*t/0.1)^2"
[time]
duration = 0.4
step = 0.0005
integrator = ")" << integrator
                      << R"("
rtol = 1e-9
atol = 1e-12
[record]
group = "zmax"
)";
  return toml;
}

/// Displacements of the top face's nodes at the samples t = k·kSample, k = 0 … kSamples (3 per node).
struct Trajectory {
  std::vector<Eigen::VectorXd> u;
  double seconds = 0.0;  ///< wall time of the run [s]
};

using Advance = std::function<Eigen::VectorXd(double)>;  // x at the given (increasing) time

Trajectory sample(const Problem& problem, const std::vector<int>& top, const Advance& advance) {
  const auto start = std::chrono::steady_clock::now();
  Trajectory out;
  for (int k = 0; k <= kSamples; ++k) {
    const Eigen::VectorXd x = k == 0 ? initial_state(problem, 0.0).x : advance(k * kSample);
    Eigen::VectorXd u(3 * static_cast<Eigen::Index>(top.size()));
    for (std::size_t n = 0; n < top.size(); ++n)
      u.segment<3>(3 * static_cast<Eigen::Index>(n)) = x.segment<3>(3 * top[n]) - problem.rest.row(top[n]).transpose();
    out.u.push_back(u);
  }
  out.seconds = sflsh::seconds_since(start);
  return out;
}

/// max_n |u_n| over the top face's nodes and the samples k in [first, last) [m].
double largest(const Trajectory& a, const Trajectory& b, std::size_t first, std::size_t last) {
  double out = 0.0;
  for (std::size_t k = first; k < std::min({last, a.u.size(), b.u.size()}); ++k) {
    for (Eigen::Index n = 0; n < a.u[k].size() / 3; ++n)
      out = std::max(out, (a.u[k].segment<3>(3 * n) - b.u[k].segment<3>(3 * n)).norm());
  }
  return out;
}

/// max_k max_n |u_a − u_b| over samples [first, last) / max_k max_n |u_reference| over the whole run.
double relative_difference(const Trajectory& a, const Trajectory& b, const Trajectory& reference, std::size_t first = 0,
                           std::size_t last = kSamples + 1) {
  const Trajectory rest{std::vector<Eigen::VectorXd>(reference.u.size(), Eigen::VectorXd::Zero(reference.u[0].size())),
                        0.0};
  return largest(a, b, first, last) / largest(reference, rest, 0, reference.u.size());
}

struct Block {
  VerifyProblem spec;
  Problem problem;
  std::vector<int> top;
};

Block load_block(const std::string& mass) {
  Block b{load_verify_problem(write_block(mass, "reference")), {}, {}};
  b.problem = make_problem(b.spec);
  b.problem.validate();
  b.top = record_nodes(b.spec);
  return b;
}

Trajectory run_reference(const Block& b) {
  ReferenceOptions options;
  options.rtol = b.spec.rtol;
  options.atol = b.spec.atol;
  options.order = 5;
  ReferenceIntegrator integrator(b.problem, options);
  integrator.initialize(initial_state(b.problem, 0.0));
  return sample(b.problem, b.top, [&](double t) { return integrator.advance_to(t).x; });
}

/// Steps of h from sample to sample with `step`, which advances the state by h and returns x.
Trajectory run_stepper(const Block& b, double h, const std::function<Eigen::VectorXd(double)>& step) {
  const long per_sample = std::lround(kSample / h);
  return sample(b.problem, b.top, [&](double) {
    Eigen::VectorXd x;
    for (long k = 0; k < per_sample; ++k) x = step(h);
    return x;
  });
}

// One block of each mass, shared by the tests below (the reference runs are the expensive part).
const Block& consistent_block() {
  static const Block block = load_block("consistent");
  return block;
}
const Trajectory& consistent_reference() {
  static const Trajectory trajectory = run_reference(consistent_block());
  return trajectory;
}

TEST(DrivenLayer, LumpedMassesDriftInPhaseFromTheConsistentReference) {
  const Block lumped_block = load_block("lumped");
  ASSERT_EQ(lumped_block.problem.mass_kind, model::MassKind::lumped);
  ASSERT_EQ(consistent_block().problem.mass_kind, model::MassKind::consistent);
  const Trajectory& consistent = consistent_reference();
  const Trajectory lumped = run_reference(lumped_block);
  const double during_drive = relative_difference(consistent, lumped, consistent, 0, 21);  // t ≤ 0.1 s
  const double last_period = relative_difference(consistent, lumped, consistent, 60);      // t ≥ 0.3 s
  const double overall = relative_difference(consistent, lumped, consistent);
  std::printf(
      "[ measured ] reference consistent %.2f s, lumped %.2f s; lumped vs consistent: %.3e (t ≤ 0.1 s), "
      "%.3e (t ≥ 0.3 s), %.3e (whole run) of the largest motion\n",
      consistent.seconds, lumped.seconds, during_drive, last_period, overall);
  // Two tets through the thickness: lumping lowers the shear mode's frequency by several per cent, and after
  // ~2 periods of free ringing the phase drift is a sizeable part of the amplitude, larger than while driven.
  // Measured: 15 % of the largest motion while driven (t ≤ 0.1 s; there the consistent mass also pushes the
  // free nodes next to the driven face back, −M_FC a_C), 127 % for t ≥ 0.3 s: the two ring out of phase.
  EXPECT_GT(overall, 0.05);
  EXPECT_GT(last_period, 1.5 * during_drive);  // the gap grows with time: a phase drift, not an offset
}

TEST(DrivenLayer, NewmarkWithConsistentMassMatchesTheReference) {
  const Block& b = consistent_block();
  const Trajectory& reference = consistent_reference();
  State initial = initial_state(b.problem, 0.0);
  sflsh::testing::TermsStepper stepper(b.problem, model::Integrator::newmark, initial);
  const double h = b.spec.step;  // 0.5 ms
  const Trajectory newmark = run_stepper(b, h, [&](double dt) {
    stepper.step(dt);
    return stepper.state().x;
  });
  const double difference = relative_difference(newmark, reference, reference);
  std::printf(
      "[ measured ] Newmark (model terms, h = %.2f ms) %.2f s; vs the consistent reference: %.3e of the "
      "largest motion\n",
      1e3 * h, newmark.seconds, difference);
  // Measured: 3.3e-3 at h = 0.5 ms and 8.2e-4 at h = 0.25 ms: Newmark's second-order time error (period error
  // (ωh)²/12 on the slab's ~10 Hz shear mode and the higher modes the drive excites) converging onto the
  // reference (rtol 1e-9, far tighter), so the two integrate the same equations — M_FC a_C of the driven face
  // included, which alone moves the top face by ~15 % of its motion (the lumped–consistent gap while driven).
  // The bound leaves 1.5× over the measured error at 0.5 ms.
  EXPECT_LT(difference, 5e-3);
}

TEST(DrivenLayer, FullSpaceNewmarkWithConsistentMassMatchesTheReference) {
  const Block& b = consistent_block();
  const double h = b.spec.step;
  // Probe: does the full-space solver honour options.integrator and problem.mass_kind yet? Until it does, it
  // runs backward Euler with lumped masses whatever it is asked, and three steps come out identical.
  auto three_steps = [&](model::Integrator integrator, model::MassKind kind) {
    Problem p = b.problem;
    p.mass_kind = kind;
    FullSpaceOptions options;
    options.integrator = integrator;
    FullSpaceSolver solver(p, MPI_COMM_WORLD, options);
    State s = initial_state(p, 0.0);
    s.a = model::initial_acceleration(p, s);
    solver.initialize(s);
    for (int k = 0; k < 3; ++k) solver.step(h);
    return solver.state().x;
  };
  const Eigen::VectorXd asked = three_steps(model::Integrator::newmark, model::MassKind::consistent);
  const Eigen::VectorXd plain = three_steps(model::Integrator::backward_euler, model::MassKind::lumped);
  if ((asked - plain).lpNorm<Eigen::Infinity>() == 0.0) {
    GTEST_SKIP() << "the full-space solver does not yet honour options.integrator / problem.mass_kind";
  }
  FullSpaceOptions options;
  options.integrator = model::Integrator::newmark;
  options.default_snes_rtol = 1e-10;
  FullSpaceSolver solver(b.problem, MPI_COMM_WORLD, options);
  State initial = initial_state(b.problem, 0.0);
  initial.a = model::initial_acceleration(b.problem, initial);
  solver.initialize(initial);
  const Trajectory full = run_stepper(b, h, [&](double dt) {
    solver.step(dt);
    return solver.state().x;
  });
  const Trajectory& reference = consistent_reference();
  const double difference = relative_difference(full, reference, reference);
  std::printf(
      "[ measured ] full-space Newmark (h = %.2f ms) %.2f s; vs the consistent reference: %.3e of the "
      "largest motion\n",
      1e3 * h, full.seconds, difference);
  EXPECT_LT(difference, 5e-3);  // as for the model-terms Newmark above: the same step definition and h
}

}  // namespace
}  // namespace sflsh::fullspace
