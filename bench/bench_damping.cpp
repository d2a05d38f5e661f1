// Benchmark: the numerical damping of fixed-step backward Euler at 30, 60, 120 and 240 fps against the
// error-controlled SUNDIALS reference, on a subject's coarse layer along a motion. All runs share one forcing:
// the motion is sampled at the finest rate and the skinning trajectory interpolates it (C¹), so the only
// difference between runs is the integrator. For each rate the per-vertex dynamics amplitude σ (docs/physics.md §4)
// is computed on that rate's own frame times, for the run and for the reference at the same times.
// Reports mean σ ratio (BE / reference), the RMS trajectory error of the skin's elastic displacement relative
// to the reference's RMS displacement, and wall time per simulated second.
// Usage: bench_damping [--subject NAME] [--motion NAME] [--seconds 1.0] [--fps 30,60,120,240]
//                      [--mesh coarse] [--rtol 1e-6] [--atol 1e-9] [--cache DIR] [--out bench_damping.json]
#include "bench_options.hpp"

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
#include <iostream>
#include <numeric>
#include <optional>

namespace {

using namespace sflsh;
using namespace sflsh::fullspace;
using namespace sflsh::model;
using Clock = std::chrono::steady_clock;

/// Skin elastic displacement (R×3) per sample.
using Samples = std::vector<RowMatrixX3d>;

Eigen::VectorXd sigma_of(const BodyLayer& layer, const Samples& samples, const RowMatrixX3d& normals) {
  (void)layer;
  DynamicsAmplitude amplitude(normals);
  for (const RowMatrixX3d& u : samples) amplitude.add(u);
  return amplitude.sigma();
}

struct DampingOptions {
  std::string subject = "OPEN_TRAIN_1", motion_name = "running_on_spot", fps_list = "30,60,120,240", mesh = "coarse";
  std::string out = "bench_damping.json", cache;
  double seconds = 1.0, rtol = 1e-6, atol = 1e-9;
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, DampingOptions& o) {
  CLI::App app{
      "The numerical damping of fixed-step backward Euler at several frame rates against the "
      "error-controlled SUNDIALS reference, on a subject's layer along a motion.",
      "bench_damping"};
  bench::use_bench_defaults(app);
  app.add_option("--subject", o.subject, "Named subject (data/open_body_subjects.toml)");
  app.add_option("--motion", o.motion_name, "Procedural motion (sflsh motion list)");
  app.add_option("--seconds", o.seconds, "Simulated time [s]");
  app.add_option("--fps", o.fps_list,
                 "Frame rates of the backward-Euler runs, comma-separated [Hz]; each divides the largest, at which "
                 "the motion and the reference are sampled")
      ->check(bench::int_list());
  app.add_option("--mesh", o.mesh, "Layer resolution: coarse | default | fine")
      ->check(bench::accepted_by("coarse|default|fine", meshing::parse_size_preset));
  app.add_option("--rtol", o.rtol, "Relative tolerance of the reference integrator");
  app.add_option("--atol", o.atol, "Absolute tolerance of the reference integrator [m]");
  app.add_option("--cache", o.cache, "Cache folder for template meshes (default $SFLSH_CACHE or ~/.cache/sflsh)");
  app.add_option("--out", o.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

/// The per-vertex normals of the layer's region surface (rows in region_surface.vertices order).
RowMatrixX3d region_normals(const BodyLayer& layer, const body::BodyModel& model) {
  RowMatrixX3d normals;
  const RowMatrixX3d all = vertex_normals(layer.shaped, model.faces);
  normals.resize(static_cast<Eigen::Index>(layer.mesh->region_surface.vertices.size()), 3);
  for (std::size_t r = 0; r < layer.mesh->region_surface.vertices.size(); ++r)
    normals.row(static_cast<Eigen::Index>(r)) = all.row(layer.mesh->region_surface.vertices[r]);
  return normals;
}

/// The reference, sampled on the finest grid.
struct Reference {
  Samples samples;
  ReferenceStats stats;
  double seconds = 0.0;
};

Reference run_reference(const BodyLayer& layer, const DampingOptions& o, int finest, int frames) {
  const Problem& problem = layer.problem;
  ReferenceOptions ref_options;
  ref_options.rtol = o.rtol;
  ref_options.atol = o.atol;
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
  return {std::move(ref_samples), st, ref_seconds};
}

/// Backward Euler at `r` fps against the reference at the same frame times: its row of the table (printed) and of
/// the JSON.
nlohmann::json measure_rate(const BodyLayer& layer, const RowMatrixX3d& normals, const Reference& ref, int r,
                            int finest, int frames, double seconds) {
  const Problem& problem = layer.problem;
  const int stride = finest / r;
  FullSpaceSolver be(problem, MPI_COMM_WORLD);
  be.initialize(initial_state(problem, 0.0));
  Samples samples{layer.surface_displacement(be.state().x)}, ref_at;
  ref_at.push_back(ref.samples[0]);
  const auto t0 = Clock::now();
  long newton = 0;
  for (int k = stride; k < frames; k += stride) {
    newton += be.step(1.0 / r).newton_iterations;
    samples.push_back(layer.surface_displacement(be.state().x));
    ref_at.push_back(ref.samples[static_cast<std::size_t>(k)]);
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
  std::cout << fmt::format("{:>6} {:>12.4f} {:>14.4f} {:>14.4f} {:>14.2f} {:>12.2f} {:>10.2f}\n", r, 1e3 * sigma.mean(),
                           1e3 * sigma_ref.mean(), ratio, 100.0 * (1.0 - ratio), 100.0 * traj, wall / seconds);
  return {{"fps", r},
          {"sigma_mean_mm", 1e3 * sigma.mean()},
          {"reference_sigma_mean_mm", 1e3 * sigma_ref.mean()},
          {"sigma_ratio", ratio},
          {"damping_percent", 100.0 * (1.0 - ratio)},
          {"trajectory_error_relative", traj},
          {"newton_per_step", static_cast<double>(newton) / static_cast<double>(samples.size() - 1)},
          {"seconds_per_simulated_second", wall / seconds}};
}

/// The layer, the reference, a row per rate, the JSON.
void run_benchmark(const DampingOptions& o) {
  PetscSession session;
  const std::vector<int> rates = bench::split_ints(o.fps_list);
  const int finest = *std::max_element(rates.begin(), rates.end());
  for (int r : rates) {
    if (finest % r != 0) throw Error(fmt::format("--fps: {} does not divide the finest rate {}", r, finest));
  }
  const body::BodyModel model = body::load_body(body::default_body_path());
  const body::Betas beta = body::find_subject(body::default_subjects(), o.subject).beta;
  const int frames = static_cast<int>(std::lround(o.seconds * finest)) + 1;
  const body::Motion motion = body::make_procedural_motion(o.motion_name, finest, frames);
  BodyLayerOptions options;
  options.size = meshing::parse_size_preset(o.mesh);
  if (!o.cache.empty()) options.cache_dir = o.cache;
  const BodyLayer layer = build_body_layer(model, beta, motion, nullptr, 12, options);
  const Problem& problem = layer.problem;
  const RowMatrixX3d normals = region_normals(layer, model);
  std::cout << fmt::format("{} on {} ({} tets, {} nodes), {} s of {}, reference rtol {:g} atol {:g}\n", o.subject,
                           o.mesh, problem.num_tets(), problem.num_nodes(), o.seconds, o.motion_name, o.rtol, o.atol);
  std::cout.flush();

  const Reference ref = run_reference(layer, o, finest, frames);

  std::cout << fmt::format("{:>6} {:>12} {:>14} {:>14} {:>14} {:>12} {:>10}\n", "fps", "sigma mm", "ref sigma mm",
                           "sigma ratio", "damping %", "traj err %", "s / sim s");
  nlohmann::json rows = nlohmann::json::array();
  for (int r : rates) rows.push_back(measure_rate(layer, normals, ref, r, finest, frames, o.seconds));
  write_json(o.out,
             {{"benchmark", "damping"},
              {"subject", o.subject},
              {"motion", o.motion_name},
              {"seconds", o.seconds},
              {"mesh", o.mesh},
              {"tets", problem.num_tets()},
              {"reference", {{"rtol", o.rtol}, {"atol", o.atol}, {"steps", ref.stats.steps}, {"seconds", ref.seconds}}},
              {"results", rows}});
  std::cout << "wrote " << o.out << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  DampingOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  try {
    run_benchmark(o);
  } catch (const std::exception& e) {
    std::cerr << "bench_damping: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
