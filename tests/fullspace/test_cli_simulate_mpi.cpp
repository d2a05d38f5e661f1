// `sflsh simulate --solver full` on two MPI processes gives the one-process result for every integrator and
// both mass kinds: the history carried in the state, the consistent mass's tet blocks and the node split
// must not change the solution beyond the solvers' tolerance.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/model/mass.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <tuple>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;
using model::Integrator;
using model::MassKind;
using sflsh::testing::run_sflsh;
using sflsh::testing::scratch_dir;

using sflsh::testing::have_mpiexec;

class CliSimulateMpi : public ::testing::TestWithParam<std::tuple<Integrator, MassKind>> {};

TEST_P(CliSimulateMpi, TwoProcessesMatchOne) {
  if (!have_mpiexec()) GTEST_SKIP() << "mpiexec not found";
  const auto [integrator, mass] = GetParam();
  const fs::path dir = scratch_dir();
  // Three frames: the first step (BDF2's backward-Euler start-up) and one step of the integrator itself.
  const std::string args = fmt::format(
      " simulate --solver full --mesh coarse --subject OPEN_TRAIN_2 --motion shake_hips --frames 3 --cache {} -q "
      "--integrator {} --mass {} --format vtk -snes_rtol 1e-12 -snes_atol 1e-13 -ksp_rtol 1e-13 --out ",
      SFLSH_TEST_CACHE, model::to_string(integrator), model::to_string(mass));
  const auto serial = run_sflsh(args + (dir / "one").string(), dir);
  ASSERT_EQ(serial.exit_code, 0) << serial.err;
  // This test process is itself an MPI singleton (PETSc is initialized): its OMPI_*/PMIX_* variables must not
  // leak into the nested mpiexec, which would otherwise try to join the singleton's session.
  const std::string mpi =
      "for v in $(env | sed -n 's/^\\(OMPI_[^=]*\\|PMIX_[^=]*\\)=.*/\\1/p'); do unset $v; done; "
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 mpiexec -n 2 " +
      std::string(SFLSH_CLI) + args + (dir / "two").string() + " >" + (dir / "mpi.log").string() + " 2>&1";
  ASSERT_EQ(std::system(mpi.c_str()), 0) << "mpiexec -n 2 failed; see " << (dir / "mpi.log");
  const vtk::Points one = vtk::read_points(dir / "one" / "body_000002.vtp");
  const vtk::Points two = vtk::read_points(dir / "two" / "body_000002.vtp");
  const Eigen::MatrixXd soft = vtk::read_point_array(dir / "one" / "body_000002.vtp", "soft_tissue_displacement");
  ASSERT_EQ(one.rows(), two.rows());
  EXPECT_GT(soft.cwiseAbs().maxCoeff(), 1e-5);  // the tissue moved (tens of micrometres to millimetres)
  EXPECT_EQ(read_json(dir / "two" / "summary.json")["solver"]["processes"].get<int>(), 2);
  // The coarse layer (25,716 dofs) is above the direct solve's 6000 and far below the 180,000 dofs from which two
  // processes take GAMG (automatic_preconditioner): ICC(0) on one process, block-Jacobi ICC on two.
  EXPECT_EQ(read_json(dir / "one" / "summary.json")["solver"]["preconditioner"], "icc");
  EXPECT_EQ(read_json(dir / "two" / "summary.json")["solver"]["preconditioner"], "bjacobi");
  // Both solve each step to ‖∇Φ‖ ≤ 1e-12 relative with inner solves to 1e-13; the preconditioners (ICC on one
  // process, block Jacobi on two) and the parallel sums differ, so the solutions differ by about that fraction
  // of a step's update (≤ 1 mm): ≤ 1e-15 m, measured 6e-17 m (the round-off of posed coordinates of ~1 m).
  // 1e-12 m is far below the tissue's motion (1e-4 m here) and far above that noise.
  EXPECT_LT((one - two).cwiseAbs().maxCoeff(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(EveryIntegratorAndMass, CliSimulateMpi,
                         ::testing::Combine(::testing::Values(Integrator::backward_euler, Integrator::bdf2,
                                                              Integrator::newmark),
                                            ::testing::Values(MassKind::lumped, MassKind::consistent)),
                         [](const auto& test) {
                           return fmt::format("{}_{}", model::to_string(std::get<0>(test.param)),
                                              model::to_string(std::get<1>(test.param)));
                         });

}  // namespace
}  // namespace sflsh::fullspace
