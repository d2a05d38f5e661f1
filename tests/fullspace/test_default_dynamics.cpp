// The default integrator and mass keep the dynamics (docs/decisions.md, "Defaults: BDF2 with consistent masses"):
// `sflsh simulate` with neither --integrator nor --mass, at the paper's 60 fps, keeps at least 95 % of the mean σ of
// the same run at 1/960 s (16 substeps per frame), in both solvers; the paper's backward Euler with lumped masses, one
// option away, does not (it keeps about three quarters over these windows), so the test tells the two apart.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <ostream>
#include <string>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::run_sflsh;
using sflsh::testing::scratch_dir;

struct Case {
  const char* solver;
  int frames;  ///< the window: 10 frames in full space (its 1/960 s run costs ~35 s), 20 for the reduced model
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.solver << ", " << c.frames << " frames"; }

class DefaultDynamics : public ::testing::TestWithParam<Case> {
 protected:
  /// Mean σ [mm] of a shake_hips run of OPEN_TEST_3 on the coarse layer (a subject and motion outside the docs'
  /// examples), with `extra` options.
  double sigma_mm(const std::string& name, const std::string& extra) {
    const auto r =
        run_sflsh(fmt::format("-q simulate --solver {} --mesh coarse --subject OPEN_TEST_3 --motion "
                              "shake_hips --frames {} --cache {} --no-output {} --out {}",
                              GetParam().solver, GetParam().frames, SFLSH_TEST_CACHE, extra, (dir_ / name).string()),
                  dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json summary = read_json(dir_ / name / "summary.json");
    return summary["dynamics"]["sigma_mean_mm"].get<double>();
  }
  const fs::path dir_ = scratch_dir();
};

TEST_P(DefaultDynamics, KeepsNinetyFivePercentOfTheConvergedSigmaAtSixtyFps) {
  const double converged = sigma_mm("converged", "--substeps 16");
  const double fast = sigma_mm("default", "");
  const double paper = sigma_mm("paper", "--integrator backward_euler --mass lumped");
  ASSERT_GT(converged, 0.5);  // the window moves the tissue (measured σ 0.99 mm full over 10 frames, 4.1 mm reduced)
  // Measured: full space 0.980 (paper 0.737), reduced 0.984 (paper 0.734). The lower bound is the 95 % the default
  // must keep; the upper one allows BDF2's small phase error to raise σ by a few percent over a short window (a
  // mild overshoot is not lost motion; 1.03 over 40 frames in full space), but not a blow-up.
  EXPECT_GE(fast / converged, 0.95) << "default σ " << fast << " mm, converged " << converged << " mm";
  EXPECT_LE(fast / converged, 1.10) << "default σ " << fast << " mm, converged " << converged << " mm";
  // The paper's configuration loses a quarter of the motion here: the test would notice a default that damps.
  EXPECT_LT(paper / converged, 0.9) << "paper σ " << paper << " mm";
}

INSTANTIATE_TEST_SUITE_P(Solvers, DefaultDynamics, ::testing::Values(Case{"full", 10}, Case{"reduced", 20}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           return std::string(param_info.param.solver);
                         });

}  // namespace
}  // namespace sflsh::fullspace
