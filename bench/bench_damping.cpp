// Benchmark: the numerical damping of fixed-step backward Euler at 30, 60, 120 and 240 fps against the
// error-controlled SUNDIALS reference, on a subject's coarse layer along a motion. All runs share one forcing:
// the motion is sampled at the finest rate and the skinning trajectory interpolates it (C¹), so the only
// difference between runs is the integrator. For each rate the per-vertex dynamics amplitude σ (docs/physics.md §4)
// is computed on that rate's own frame times, for the run and for the reference at the same times.
// Reports mean σ ratio (BE / reference), the RMS trajectory error of the skin's elastic displacement relative
// to the reference's RMS displacement, and wall time per simulated second.
// Usage: bench_damping [--subject NAME] [--motion NAME] [--seconds 1.0] [--fps 30,60,120,240]
//                      [--mesh coarse] [--rtol 1e-6] [--atol 1e-9] [--cache DIR] [--out bench_damping.json]
#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/petsc_session.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/simulation_output.hpp>

#include <fmt/format.h>

#include <chrono>
#include <cstring>
#include <iostream>
#include <numeric>
#include <sstream>

namespace {

using namespace sflsh;
using namespace sflsh::fullspace;
using namespace sflsh::model;
using Clock = std::chrono::steady_clock;

std::vector<int> split_ints(const std::string& csv) {
  std::vector<int> out;
  std::stringstream stream(csv);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) out.push_back(std::stoi(item));
  return out;
}

/// Skin elastic displacement (R×3) per sample.
using Samples = std::vector<RowMatrixX3d>;

Eigen::VectorXd sigma_of(const BodyLayer& layer, const Samples& samples, const RowMatrixX3d& normals) {
  (void)layer;
  DynamicsAmplitude amplitude(normals);
  for (const RowMatrixX3d& u : samples) amplitude.add(u);
  return amplitude.sigma();
}

}  // namespace

int main(int argc, char** argv) {
  std::string subject = "OPEN_TRAIN_1", motion_name = "running_on_spot", fps_list = "30,60,120,240", mesh = "coarse";
  std::string out = "bench_damping.json", cache;
  double seconds = 1.0, rtol = 1e-6, atol = 1e-9;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--subject")
      subject = value;
    else if (key == "--motion")
      motion_name = value;
    else if (key == "--seconds")
      seconds = std::stod(value);
    else if (key == "--fps")
      fps_list = value;
    else if (key == "--mesh")
      mesh = value;
    else if (key == "--rtol")
      rtol = std::stod(value);
    else if (key == "--atol")
      atol = std::stod(value);
    else if (key == "--cache")
      cache = value;
    else if (key == "--out")
      out = value;
    else {
      std::cerr << "bench_damping: unknown option " << key << "\n";
      return 2;
    }
  }
  try {
    PetscSession session;
    const std::vector<int> rates = split_ints(fps_list);
    const int finest = *std::max_element(rates.begin(), rates.end());
    for (int r : rates) {
      if (finest % r != 0) throw Error(fmt::format("--fps: {} does not divide the finest rate {}", r, finest));
    }
    const body::BodyModel model = body::load_body(body::default_body_path());
    const body::Betas beta = body::find_subject(body::default_subjects(), subject).beta;
    const int frames = static_cast<int>(std::lround(seconds * finest)) + 1;
    const body::Motion motion = body::make_procedural_motion(motion_name, finest, frames);
    BodyLayerOptions options;
    options.size = meshing::parse_size_preset(mesh);
    if (!cache.empty()) options.cache_dir = cache;
    const BodyLayer layer = build_body_layer(model, beta, motion, nullptr, 12, options);
    const Problem& problem = layer.problem;
    RowMatrixX3d normals;
    {
      const RowMatrixX3d all = vertex_normals(layer.shaped, model.faces);
      normals.resize(static_cast<Eigen::Index>(layer.mesh->region_surface.vertices.size()), 3);
      for (std::size_t r = 0; r < layer.mesh->region_surface.vertices.size(); ++r)
        normals.row(static_cast<Eigen::Index>(r)) = all.row(layer.mesh->region_surface.vertices[r]);
    }
    std::cout << fmt::format("{} on {} ({} tets, {} nodes), {} s of {}, reference rtol {:g} atol {:g}\n", subject, mesh,
                             problem.num_tets(), problem.num_nodes(), seconds, motion_name, rtol, atol);
    std::cout.flush();

    // The reference, sampled on the finest grid.
    ReferenceOptions ref_options;
    ref_options.rtol = rtol;
    ref_options.atol = atol;
    ReferenceIntegrator reference(problem, ref_options);
    const State start = initial_state(problem, 0.0);
    reference.initialize(start);
    Samples ref_samples{layer.surface_displacement(start.x)};
    const auto t_ref = Clock::now();
    for (int k = 1; k < frames; ++k) {
      ref_samples.push_back(layer.surface_displacement(reference.advance_to(static_cast<double>(k) / finest).x));
      if (k % std::max(1, finest / 10) == 0 || k == frames - 1) {
        std::cout << fmt::format("  reference at t = {:.3f} s: {} steps, {:.1f} s\n", static_cast<double>(k) / finest,
                                 reference.stats().steps, sflsh::seconds_since(t_ref));
        std::cout.flush();
      }
    }
    const double ref_seconds = sflsh::seconds_since(t_ref);
    const ReferenceStats& st = reference.stats();
    std::cout << fmt::format("reference: {} steps, {} Jacobians, {:.1f} s\n\n", st.steps, st.jac_evals, ref_seconds);
    std::cout.flush();

    std::cout << fmt::format("{:>6} {:>12} {:>14} {:>14} {:>14} {:>12} {:>10}\n", "fps", "sigma mm", "ref sigma mm",
                             "sigma ratio", "damping %", "traj err %", "s / sim s");
    nlohmann::json rows = nlohmann::json::array();
    for (int r : rates) {
      const int stride = finest / r;
      FullSpaceSolver be(problem, MPI_COMM_WORLD);
      be.initialize(initial_state(problem, 0.0));
      Samples samples{layer.surface_displacement(be.state().x)}, ref_at;
      ref_at.push_back(ref_samples[0]);
      const auto t0 = Clock::now();
      long newton = 0;
      for (int k = stride; k < frames; k += stride) {
        newton += be.step(1.0 / r).newton_iterations;
        samples.push_back(layer.surface_displacement(be.state().x));
        ref_at.push_back(ref_samples[static_cast<std::size_t>(k)]);
      }
      const double wall = sflsh::seconds_since(t0);
      const Eigen::VectorXd sigma = sigma_of(layer, samples, normals), sigma_ref = sigma_of(layer, ref_at, normals);
      double err2 = 0.0, ref2 = 0.0;
      for (std::size_t k = 0; k < samples.size(); ++k) {
        err2 += (samples[k] - ref_at[k]).squaredNorm();
        ref2 += ref_at[k].squaredNorm();
      }
      const double ratio = sigma.mean() / sigma_ref.mean();
      const double traj = ref2 > 0 ? std::sqrt(err2 / ref2) : 0.0;
      std::cout << fmt::format("{:>6} {:>12.4f} {:>14.4f} {:>14.4f} {:>14.2f} {:>12.2f} {:>10.2f}\n", r,
                               1e3 * sigma.mean(), 1e3 * sigma_ref.mean(), ratio, 100.0 * (1.0 - ratio), 100.0 * traj,
                               wall / seconds);
      rows.push_back({{"fps", r},
                      {"sigma_mean_mm", 1e3 * sigma.mean()},
                      {"reference_sigma_mean_mm", 1e3 * sigma_ref.mean()},
                      {"sigma_ratio", ratio},
                      {"damping_percent", 100.0 * (1.0 - ratio)},
                      {"trajectory_error_relative", traj},
                      {"newton_per_step", static_cast<double>(newton) / static_cast<double>(samples.size() - 1)},
                      {"seconds_per_simulated_second", wall / seconds}});
    }
    write_json(out, {{"benchmark", "damping"},
                     {"subject", subject},
                     {"motion", motion_name},
                     {"seconds", seconds},
                     {"mesh", mesh},
                     {"tets", problem.num_tets()},
                     {"reference", {{"rtol", rtol}, {"atol", atol}, {"steps", st.steps}, {"seconds", ref_seconds}}},
                     {"results", rows}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_damping: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
