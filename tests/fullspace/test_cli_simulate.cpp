// The `sflsh simulate --solver full|reduced` contract, the same for both solvers: the posed surface per frame
// in `sflsh motion export`'s layout (same points, same order, same .pvd with --format vtk), the default compact
// xdmf series (Float32, zlib, the display arrays), the extra fields, summary.json, --no-output, and clear errors.
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "self_described.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_reader.hpp>
#include <sflsh/model/simulation_output.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <utility>
#include <vector>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::run_sflsh;
using sflsh::testing::scratch_dir;

std::string common() {
  return fmt::format("--subject OPEN_TRAIN_2 --motion shake_hips --frames 4 --cache {} -q", SFLSH_TEST_CACHE);
}

class CliSimulate : public ::testing::TestWithParam<const char*> {
 protected:
  std::string solver() const { return std::string("simulate --solver ") + GetParam() + " "; }
};

TEST_P(CliSimulate, SurfaceMatchesMotionExportLayoutAndCarriesTheSoftTissueFields) {
  const fs::path dir = scratch_dir();
  const auto sim =
      run_sflsh(solver() + "--mesh coarse " + common() + " --format vtk --write-layer --out " + (dir / "sim").string(),
                dir);  // --format vtk: the .pvd layout of `motion export`, with every array by default
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const auto exp = run_sflsh(
      "motion export --subject OPEN_TRAIN_2 --motion shake_hips --frames 4 -q --out " + (dir / "exp").string(), dir);
  ASSERT_EQ(exp.exit_code, 0) << exp.err;
  for (const char* file : {"body.pvd", "body_000000.vtp", "body_000003.vtp", "layer.pvd", "layer_000003.vtu",
                           "dynamics.vtp", "summary.json"}) {
    EXPECT_TRUE(fs::exists(dir / "sim" / file)) << file;
  }
  // Frame 0 is the rest state: the same points as the export to round-off. Later frames differ by the soft
  // tissue only, and soft_tissue_displacement is exactly that difference.
  const vtk::Points rest_sim = vtk::read_points(dir / "sim" / "body_000000.vtp");
  const vtk::Points rest_exp = vtk::read_points(dir / "exp" / "body_000000.vtp");
  ASSERT_EQ(rest_sim.rows(), rest_exp.rows());
  EXPECT_LT((rest_sim - rest_exp).cwiseAbs().maxCoeff(), 1e-9);
  const vtk::Points last_sim = vtk::read_points(dir / "sim" / "body_000003.vtp");
  const vtk::Points last_exp = vtk::read_points(dir / "exp" / "body_000003.vtp");
  const Eigen::MatrixXd soft = vtk::read_point_array(dir / "sim" / "body_000003.vtp", "soft_tissue_displacement");
  EXPECT_LT(((last_sim - last_exp) - soft).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(soft.cwiseAbs().maxCoeff(), 0.0);  // the tissue moved
  const std::vector<std::string> names = vtk::read_point_array_names(dir / "sim" / "body_000003.vtp");
  for (const char* field : {"displacement", "velocity", "skin_weights_argmax", "soft_tissue_displacement",
                            "elastic_displacement", "strain_energy_density", "thickness", "thickness_fraction",
                            "young_tangent", "young_normal", "soft_region", "Normals"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), field), names.end()) << field;
  }
  for (const char* file : {"body_000003.vtp", "dynamics.vtp"})
    sflsh::testing::expect_self_described(dir / "sim" / file);
  const nlohmann::json summary = read_json(dir / "sim" / "summary.json");
  ASSERT_EQ(summary["frames"].size(), 4u);
  EXPECT_GT(summary["solver"]["newton_iterations"].get<int>(), 0);
  EXPECT_TRUE(summary["frames"][3].contains("linear_iterations"));
  EXPECT_FALSE(summary["frames"][3].contains("energy"));  // per-frame energies only with --energies
  EXPECT_TRUE(summary["timings"].contains("seconds_per_frame"));
  EXPECT_GE(summary["dynamics"]["sigma_mean_mm"].get<double>(), 0.0);
  EXPECT_EQ(summary["solver"]["name"].get<std::string>(), GetParam());
  // The defaults (docs/decisions.md, "Defaults: BDF2 with consistent masses"); the paper's backward Euler + lumped is
  // one option away (IntegratorAndMassAreChosenAndRecorded).
  EXPECT_EQ(summary["integrator"].get<std::string>(), "bdf2");
  EXPECT_EQ(summary["mass"].get<std::string>(), "consistent");
  if (std::string(GetParam()) == "reduced") {
    EXPECT_EQ(summary["reduced"]["point_handles"].get<int>(), 86);
    EXPECT_EQ(summary["reduced"]["coordinates"].get<int>(), 258);
    EXPECT_GE(summary["reduced"]["cubature"].get<int>(), 200);
    EXPECT_TRUE(summary["timings"].contains("elastic_seconds"));
  }
}

/// A float64 dataset of an HDF5 file, row-major.
std::vector<double> read_h5(const fs::path& file, const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // a missing dataset is an expected answer here, not an error to print
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  std::vector<double> values;
  if (d >= 0) {
    const hid_t space = H5Dget_space(d);
    values.resize(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Sclose(space);
    H5Dclose(d);
  }
  H5Fclose(f);
  return values;
}

TEST_P(CliSimulate, XdmfSeriesHoldsTheSameFramesAsTheVtkSeries) {
  const fs::path dir = scratch_dir();
  const auto vtk_run =
      run_sflsh(solver() + "--mesh coarse " + common() + " --format vtk --out " + (dir / "vtk").string(), dir);
  ASSERT_EQ(vtk_run.exit_code, 0) << vtk_run.err;
  const auto xdmf_run =
      run_sflsh(solver() + "--mesh coarse " + common() +
                    " --format xdmf --precision float64 --fields all --write-layer --out " + (dir / "xdmf").string(),
                dir);
  ASSERT_EQ(xdmf_run.exit_code, 0) << xdmf_run.err;
  for (const char* file : {"body.xmf", "body.h5", "layer.xmf", "layer.h5", "dynamics.vtp", "summary.json"})
    EXPECT_TRUE(fs::exists(dir / "xdmf" / file)) << file;
  EXPECT_FALSE(fs::exists(dir / "xdmf" / "body_000000.vtp"));
  // The same solve written two ways: the posed surface and the soft-tissue field of the last frame agree to the
  // solvers' noise. Two processes solving the same steps to ‖∇Φ‖ ≤ 1e-12 relative may sum in another order
  // (threads), which moves positions of ~1 m by round-off (≤ 1e-15 m, as in CliSimulateMpi); 1e-12 m is far
  // above that and far below the tissue's motion (≥ 1e-5 m here). Float64 datasets lose nothing on the way.
  const vtk::Points last = vtk::read_points(dir / "vtk" / "body_000003.vtp");
  const std::vector<double> geometry = read_h5(dir / "xdmf" / "body.h5", "/geometry/000003");
  ASSERT_EQ(geometry.size(), static_cast<std::size_t>(last.size()));
  EXPECT_LT((Eigen::Map<const vtk::Points>(geometry.data(), last.rows(), 3) - last).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd soft = vtk::read_point_array(dir / "vtk" / "body_000003.vtp", "soft_tissue_displacement");
  const std::vector<double> soft_h5 = read_h5(dir / "xdmf" / "body.h5", "/point/soft_tissue_displacement/000003");
  ASSERT_EQ(soft_h5.size(), static_cast<std::size_t>(soft.size()));
  EXPECT_GT(soft.cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT((Eigen::Map<const vtk::Points>(soft_h5.data(), soft.rows(), 3) - vtk::Points(soft)).cwiseAbs().maxCoeff(),
            1e-12);
  // Fixed fields once, not per frame.
  EXPECT_FALSE(read_h5(dir / "xdmf" / "body.h5", "/static/point/young_tangent").empty());
  EXPECT_TRUE(read_h5(dir / "xdmf" / "body.h5", "/point/young_tangent/000003").empty());
  EXPECT_FALSE(read_h5(dir / "xdmf" / "body.h5", "/static/point/soft_region").empty());
  EXPECT_FALSE(read_h5(dir / "xdmf" / "body.h5", "/point/Normals/000003").empty());
  std::ifstream xmf(dir / "xdmf" / "body.xmf");
  const std::string xml((std::istreambuf_iterator<char>(xmf)), std::istreambuf_iterator<char>());
  EXPECT_NE(xml.find("<Information Name=\"units\" Value=\"skin_weights_argmax: index; thickness_fraction: 1; "),
            std::string::npos);
  const nlohmann::json summary = read_json(dir / "xdmf" / "summary.json");
  EXPECT_EQ(summary["output"]["format"], "xdmf");
  EXPECT_EQ(summary["output"]["series"], "body.xmf");
}

TEST_P(CliSimulate, DefaultOutputIsACompactXdmfSeriesOfTheDisplayArrays) {
  const fs::path dir = scratch_dir();
  const auto run =
      run_sflsh(solver() + "--mesh coarse " + common() + " --write-layer --out " + (dir / "d").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto exp = run_sflsh(
      "motion export --subject OPEN_TRAIN_2 --motion shake_hips --frames 4 -q --out " + (dir / "exp").string(), dir);
  ASSERT_EQ(exp.exit_code, 0) << exp.err;
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir / "d")) files.push_back(entry.path().filename().string());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files,
            (std::vector<std::string>{"body.h5", "body.xmf", "dynamics.vtp", "layer.h5", "layer.xmf", "summary.json"}));
  const xdmf::SeriesReader body(dir / "d" / "body.xmf");
  ASSERT_EQ(body.steps(), 4u);
  // Float32 positions of a body ~1 m across: rounding ≤ 2⁻²⁴ · 2 m ≈ 1.2e-7 m; the rest frame is the export's.
  const vtk::Points rest = vtk::read_points(dir / "exp" / "body_000000.vtp");
  EXPECT_LT((body.points(0) - rest).cwiseAbs().maxCoeff(), 2e-7);
  // The last frame differs from the export's by the soft tissue alone, each to Float32 rounding.
  const vtk::Points last = vtk::read_points(dir / "exp" / "body_000003.vtp");
  const Eigen::MatrixXd soft = body.point_array(3, "soft_tissue_displacement");
  EXPECT_GT(soft.cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT(((body.points(3) - last) - soft).cwiseAbs().maxCoeff(), 4e-7);
  EXPECT_THAT(
      body.point_array_names(3),
      ::testing::UnorderedElementsAre("skin_weights_argmax", "thickness_fraction", "young_tangent", "young_normal",
                                      "soft_region", "soft_tissue_displacement", "strain_energy_density", "Normals"));
  const xdmf::SeriesReader layer(dir / "d" / "layer.xmf");
  EXPECT_EQ(layer.steps(), 4u);
  EXPECT_EQ(layer.cells().cols(), 4);
  const nlohmann::json summary = read_json(dir / "d" / "summary.json");
  EXPECT_EQ(summary["output"]["format"], "xdmf");
  EXPECT_EQ(summary["output"]["precision"], "float32");
  EXPECT_EQ(summary["output"]["compression"], "zlib");
  EXPECT_EQ(summary["output"]["fields"].size(), model::default_frame_fields().size());
  // --fields all brings every array back; lz4 is refused for an xdmf series in one line, leaving nothing.
  const auto all =
      run_sflsh(solver() + "--mesh coarse " + common() + " --fields all --out " + (dir / "a").string(), dir);
  ASSERT_EQ(all.exit_code, 0) << all.err;
  EXPECT_THAT(
      xdmf::SeriesReader(dir / "a" / "body.xmf").point_array_names(3),
      ::testing::IsSupersetOf({"displacement", "velocity", "elastic_displacement", "soft_tissue_displacement"}));
  const auto lz4 =
      run_sflsh(solver() + "--mesh coarse " + common() + " --compression lz4 --out " + (dir / "z").string(), dir);
  EXPECT_EQ(lz4.exit_code, 1);
  EXPECT_THAT(lz4.err, ::testing::HasSubstr("--compression lz4: HDF5 has no LZ4 filter here"));
  EXPECT_FALSE(fs::exists(dir / "z"));
}

TEST_P(CliSimulate, NoOutputWritesOnlyTheSummary) {
  const fs::path dir = scratch_dir();
  const auto r = run_sflsh(solver() + "--mesh coarse " + common() + " --no-output --out " + (dir / "o").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir / "o")) files.push_back(entry.path().filename().string());
  EXPECT_EQ(files, std::vector<std::string>{"summary.json"});
}

TEST_P(CliSimulate, BadArgumentsGiveOneLineErrorsAndNoOutput) {
  const fs::path dir = scratch_dir();
  const auto motion =
      run_sflsh(solver() + "--subject OPEN_TRAIN_2 --motion no_such_motion --out " + (dir / "a").string(), dir);
  EXPECT_NE(motion.exit_code, 0);
  EXPECT_NE(motion.err.find("no_such_motion"), std::string::npos) << motion.err;
  EXPECT_FALSE(fs::exists(dir / "a" / "summary.json"));
  const auto density = run_sflsh(solver() + common() + " --density -1 --out " + (dir / "b").string(), dir);
  EXPECT_NE(density.exit_code, 0);
  EXPECT_NE(density.err.find("--density"), std::string::npos) << density.err;
  // Counts and rates state both bounds (issue 45: "--substeps must be an integer ≥ 1" although 10⁶ was the limit).
  for (const auto& [option, expected] : std::vector<std::pair<std::string, std::string>>{
           {"--substeps 1000000000", "--substeps must be an integer in [1, 10⁶], got 1000000000"},
           {"--substeps 0", "--substeps must be an integer in [1, 10⁶], got 0"},
           {"--handles 0", "--handles must be an integer in [1, 10⁶], got 0"},
           {"--fps 1e9", "--fps must be in (0, 10000] frames per second, got 1000000000"}}) {
    const auto r = run_sflsh(solver() + common() + " " + option + " --out " + (dir / "d").string(), dir);
    EXPECT_EQ(r.exit_code, 1) << option;
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "d"));
  }
  if (std::string(GetParam()) == "reduced") {
    const auto handles =
        run_sflsh(solver() + "--mesh coarse " + common() + " --handles 100000 --out " + (dir / "c").string(), dir);
    EXPECT_NE(handles.exit_code, 0);
    EXPECT_NE(handles.err.find("point handles"), std::string::npos) << handles.err;
    EXPECT_FALSE(fs::exists(dir / "c" / "summary.json"));
  }
}

// Any integrator and mass are one option away, the paper's backward Euler + lumped among them (named so in --help).
TEST_P(CliSimulate, IntegratorAndMassAreChosenAndRecorded) {
  const fs::path dir = scratch_dir();
  for (const auto& [integrator, mass] :
       std::vector<std::pair<std::string, std::string>>{{"newmark", "consistent"}, {"backward_euler", "lumped"}}) {
    SCOPED_TRACE(integrator);
    const fs::path out = dir / integrator;
    const auto r = run_sflsh(solver() + "--mesh coarse " + common() + " --integrator " + integrator + " --mass " +
                                 mass + " --no-output --out " + out.string(),
                             dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json summary = read_json(out / "summary.json");
    EXPECT_EQ(summary["integrator"].get<std::string>(), integrator);
    EXPECT_EQ(summary["mass"].get<std::string>(), mass);
    EXPECT_EQ(summary["solver"]["integrator"].get<std::string>(), integrator);
    EXPECT_EQ(summary["frames"].size(), 4u);
  }
  const auto help = run_sflsh("simulate --help", dir);
  EXPECT_THAT(help.out, ::testing::HasSubstr("backward_euler (the paper's"));
  EXPECT_THAT(help.out, ::testing::HasSubstr("lumped (the paper's"));
}

// Energies on request: every frame carries kinetic, elastic and gravitational energy, and asking for them changes
// nothing else in the run (the same σ, iterations and frames, bit for bit).
TEST_P(CliSimulate, EnergiesOnRequestLeaveTheRunUnchanged) {
  const fs::path dir = scratch_dir();
  const std::string base = solver() + "--mesh coarse " + common() + " --no-output --out ";
  const auto plain = run_sflsh(base + (dir / "plain").string(), dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto with = run_sflsh(base + (dir / "with").string() + " --energies", dir);
  ASSERT_EQ(with.exit_code, 0) << with.err;
  const nlohmann::json a = read_json(dir / "plain" / "summary.json"), b = read_json(dir / "with" / "summary.json");
  EXPECT_EQ(a["dynamics"], b["dynamics"]);
  EXPECT_EQ(a["solver"]["newton_iterations"], b["solver"]["newton_iterations"]);
  ASSERT_EQ(b["frames"].size(), 4u);
  for (std::size_t f = 1; f < 4; ++f) {
    const nlohmann::json& e = b["frames"][f]["energy"];
    EXPECT_GT(e["kinetic"].get<double>(), 0.0) << f;
    EXPECT_GE(e["elastic"].get<double>(), 0.0) << f;
    EXPECT_TRUE(std::isfinite(e["gravity"].get<double>())) << f;
    EXPECT_EQ(a["frames"][f]["newton_iterations"], b["frames"][f]["newton_iterations"]) << f;
    EXPECT_FALSE(a["frames"][f].contains("energy")) << f;
  }
}

TEST_P(CliSimulate, UnknownIntegratorOrMassIsOneLineNamingTheOptionAndTheChoices) {
  const fs::path dir = scratch_dir();
  const auto integrator =
      run_sflsh(solver() + "--mesh coarse " + common() + " --integrator rk4 --out " + (dir / "a").string(), dir);
  EXPECT_NE(integrator.exit_code, 0);
  EXPECT_NE(integrator.err.find("--integrator"), std::string::npos) << integrator.err;
  EXPECT_NE(integrator.err.find("backward_euler, bdf2, newmark"), std::string::npos) << integrator.err;
  EXPECT_EQ(std::count(integrator.err.begin(), integrator.err.end(), '\n'), 1) << integrator.err;
  EXPECT_FALSE(fs::exists(dir / "a" / "summary.json"));
  const auto mass =
      run_sflsh(solver() + "--mesh coarse " + common() + " --mass heavy --out " + (dir / "b").string(), dir);
  EXPECT_NE(mass.exit_code, 0);
  EXPECT_NE(mass.err.find("--mass"), std::string::npos) << mass.err;
  EXPECT_NE(mass.err.find("lumped, consistent"), std::string::npos) << mass.err;
  EXPECT_EQ(std::count(mass.err.begin(), mass.err.end(), '\n'), 1) << mass.err;
  EXPECT_FALSE(fs::exists(dir / "b" / "summary.json"));
}

INSTANTIATE_TEST_SUITE_P(Solvers, CliSimulate, ::testing::Values("full", "reduced"));

}  // namespace
}  // namespace sflsh::fullspace
