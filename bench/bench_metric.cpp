// Benchmark and recovery table of the dynamics metric (docs/validate.md "Recovery of known dynamics"): synthetic
// DYNA-layout sequences with known localized soft-tissue motion (synthetic_dyna.hpp) over procedural poses, the
// pose (and β) fit, σ by inverse skinning, against the known σ.
// Usage: bench_metric [--body PATH] [--frames N] [--table] [--out results.json]
//   default: the timing case (300 frames of running_on_spot, every region, 6 mm at 3 Hz), β given and fitted,
//            the rigidity fit and the earlier soft-weight fit;
//   --table: the recovery table over motions × regions × amplitude/frequency × β given/fitted, both fits.
// Prints a Markdown table and writes JSON (true and recovered mean σ over the soft region [mm], error [%],
// Pearson correlation of σ per soft-region vertex, seconds of fit + metric).
#include "bench_options.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/validate/registration_metrics.hpp>
#include <sflsh/validate/synthetic_dyna.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>
#include <string>

namespace {

using namespace sflsh;

struct Case {
  std::string motion;
  std::vector<std::string> regions;
  double amplitude_mm, frequency;
};

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : "+") + n;
  return out;
}

/// The joint that weighs most in vertex i's skinning.
int dominant_joint(const body::BodyModel& model, Eigen::Index i) {
  Eigen::Index joint = 0;
  model.weights.row(i).maxCoeff(&joint);
  return static_cast<int>(joint);
}

/// --diagnose (stderr): where the error of the recovered σ sits. Per joint, the fitted local rotation's error
/// e_t = log(R_fit,t R_true,tᵀ) about its mean over t (the part that moves with time and so enters σ) [mrad RMS],
/// and the sum over the soft vertices skinned mostly to that joint of σ_recovered − σ_true, split into still and
/// moving vertices, as a share of the mean's error (Σ over groups = N_soft × error of the mean).
void print_diagnosis(const body::BodyModel& model, const validate::SyntheticSoftSequence& s,
                     const validate::RegistrationMetrics& m) {
  const auto frames = s.motion.poses.size();
  std::vector<char> moving(static_cast<std::size_t>(model.num_vertices()), 0);
  for (int v : s.moving_vertices) moving[static_cast<std::size_t>(v)] = 1;
  std::array<double, body::kNumJoints> still_excess{}, moving_excess{};
  std::array<int, body::kNumJoints> still_count{}, moving_count{};
  double total_excess = 0.0;
  for (int v : s.truth.soft_vertices) {
    const int j = dominant_joint(model, v);
    const double excess = m.dynamics.sigma[v] - s.truth.sigma[v];
    total_excess += excess;
    if (moving[static_cast<std::size_t>(v)]) {
      moving_excess[static_cast<std::size_t>(j)] += excess;
      ++moving_count[static_cast<std::size_t>(j)];
    } else {
      still_excess[static_cast<std::size_t>(j)] += excess;
      ++still_count[static_cast<std::size_t>(j)];
    }
  }
  std::cerr << fmt::format("  diagnosis: Σ(σ_rec − σ_true) over the soft region {:.3f} mm\n", 1e3 * total_excess);
  std::cerr << "  joint            | rot. error [mrad] | still: n, Σ excess [mm] | moving: n, Σ excess [mm]\n";
  for (int j = 0; j < body::kNumJoints; ++j) {
    std::vector<Eigen::Vector3d> error(frames);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t t = 0; t < frames; ++t) {
      const Eigen::Matrix3d fit = body::rodrigues(m.fit.motion.poses[t].segment<3>(3 * j));
      const Eigen::Matrix3d truth = body::rodrigues(s.motion.poses[t].segment<3>(3 * j));
      const Eigen::AngleAxisd difference(Eigen::Matrix3d(fit * truth.transpose()));
      error[t] = difference.angle() * difference.axis();
      mean += error[t] / static_cast<double>(frames);
    }
    double square = 0.0;
    for (const Eigen::Vector3d& e : error) square += (e - mean).squaredNorm();
    const auto k = static_cast<std::size_t>(j);
    std::cerr << fmt::format("  {:16} | {:17.3f} | {:4d} {:+18.3f} | {:4d} {:+19.3f}\n", body::kJointNames[k],
                             1e3 * std::sqrt(square / static_cast<double>(frames)), still_count[k],
                             1e3 * still_excess[k], moving_count[k], 1e3 * moving_excess[k]);
  }
}

struct MetricOptions {
  std::string body_path, out = "bench_metric.json";
  int frames = 300;
  bool table = false, only_rigidity = false, diagnose = false;
  Case single{"running_on_spot", validate::soft_motion_region_names(), 6.0, 3.0};  // --motion, --amplitude, --frequency
  validate::PoseFitOptions tuned;  // --rigid-depth, --temporal-weight, --min-weight, --stride
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, MetricOptions& o) {
  CLI::App app{
      "Benchmark and recovery table of the dynamics metric: synthetic DYNA-layout sequences with known "
      "soft-tissue motion, the pose (and β) fit, σ by inverse skinning, against the known σ.",
      "bench_metric"};
  bench::use_bench_defaults(app);
  app.add_option("--body", o.body_path, "Body model .npz in SMPL layout (default: the open body, data/open_body.npz)");
  app.add_option("--frames", o.frames, "Frames of each sequence");
  app.add_flag("--table", o.table,
               "The recovery table over motions × regions × amplitude/frequency × β given/fitted instead of the "
               "timing case");
  app.add_flag("--rigidity-only", o.only_rigidity, "Only the rigidity fit (the default one), not the soft-weight fit");
  app.add_flag("--diagnose", o.diagnose, "Per joint, where the error of the recovered σ sits (stderr)");
  app.add_option("--motion", o.single.motion, "Timing case: procedural motion (sflsh motion list)");
  app.add_option("--amplitude", o.single.amplitude_mm, "Timing case: amplitude of the soft-tissue motion [mm]");
  app.add_option("--frequency", o.single.frequency, "Timing case: frequency of the soft-tissue motion [Hz]");
  app.add_option_function<std::string>(
      "--region", [&o](const std::string& region) { o.single.regions = {region}; },
      "Timing case: the one region that moves (default: every soft-motion region)");
  app.add_option("--rigid-depth", o.tuned.rigid_depth,
                 "Rigidity fit: D_0 [m], soft vertices nearer the bones count as rigid");
  app.add_option("--temporal-weight", o.tuned.temporal_weight,
                 "Rigidity fit: λ_θ [m²/rad²] of the second-difference prior on θ");
  app.add_option("--min-weight", o.tuned.min_weight, "Rigidity fit: vertices weighing less are left out of the fit");
  app.add_option("--passes", o.tuned.reweighting_passes, "Rigidity fit: reweighted refits");
  app.add_option("--min-motion-scale", o.tuned.min_motion_scale, "Rigidity fit: least σ_0 [m] of the reweighting");
  app.add_option("--min-reweight", o.tuned.min_reweight, "Rigidity fit: f_min, the reweighting factor's floor");
  app.add_option("--stride", o.tuned.vertex_stride, "Fit on vertices 0, s, 2s, … (1: every vertex)");
  app.add_option("--out", o.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

/// The timing case, or with --table the recovery table's cases.
std::vector<Case> make_cases(const MetricOptions& o) {
  const std::vector<std::string> all = validate::soft_motion_region_names();
  std::vector<Case> cases;
  if (!o.table) {
    cases.push_back(o.single);
  } else {
    for (const std::string& motion : body::procedural_motion_names()) cases.push_back({motion, all, 6.0, 3.0});
    for (const std::string& region : all) cases.push_back({"running_on_spot", {region}, 6.0, 3.0});
    for (const auto& [a, f] : std::vector<std::pair<double, double>>{{2.0, 2.0}, {2.0, 6.0}, {8.0, 2.0}, {8.0, 6.0}})
      cases.push_back({"shake_hips", all, a, f});
  }
  return cases;
}

/// Where the error sits (stderr): mean σ over the moving vertices and over the still soft vertices [mm].
void print_moving_and_still(const body::BodyModel& model, const validate::SyntheticSoftSequence& s,
                            const validate::RegistrationMetrics& m) {
  std::vector<char> moving(static_cast<std::size_t>(model.num_vertices()), 0);
  for (int v : s.moving_vertices) moving[static_cast<std::size_t>(v)] = 1;
  double still_sum = 0.0, moving_true = 0.0, moving_recovered = 0.0;
  int still = 0;
  for (int v : s.truth.soft_vertices) {
    if (moving[static_cast<std::size_t>(v)]) {
      moving_true += s.truth.sigma[v];
      moving_recovered += m.dynamics.sigma[v];
    } else {
      still_sum += m.dynamics.sigma[v];
      ++still;
    }
  }
  const auto moving_count = static_cast<double>(std::max<std::size_t>(s.moving_vertices.size(), 1));
  std::cerr << fmt::format("  moving: true {:.3f}, recovered {:.3f} mm; still soft vertices: {:.3f} mm\n",
                           1e3 * moving_true / moving_count, 1e3 * moving_recovered / moving_count,
                           1e3 * still_sum / std::max(still, 1));
}

/// One case: its sequence, then each fit with β given and fitted; the rows of the table (printed) and of the JSON.
void measure_case(const body::BodyModel& model, const Case& c, const MetricOptions& o, nlohmann::json& results) {
  validate::SyntheticSoftMotion spec;
  spec.motion = c.motion;
  spec.frames = o.frames;
  spec.regions = c.regions;
  spec.amplitude = 1e-3 * c.amplitude_mm;
  spec.frequency = c.frequency;
  const validate::SyntheticSoftSequence s = validate::synthetic_soft_motion(model, spec);
  const double truth = s.truth.mean_sigma_soft();
  for (const bool beta_given : {true, false})
    for (const validate::PoseFitWeighting weighting :
         {validate::PoseFitWeighting::soft_weight, validate::PoseFitWeighting::rigidity}) {
      if (o.only_rigidity && weighting != validate::PoseFitWeighting::rigidity) continue;
      validate::PoseFitOptions options = o.tuned;
      options.weighting = weighting;
      const auto t0 = std::chrono::steady_clock::now();
      const validate::RegistrationMetrics m = validate::registration_metrics(
          model, s.frames, spec.fps, beta_given ? std::optional<body::Betas>(s.beta) : std::nullopt, options);
      const double seconds = sflsh::seconds_since(t0);
      const double recovered = m.dynamics.mean_sigma_soft();
      const double error = 100.0 * (recovered - truth) / truth;
      const double r = validate::sigma_correlation(s.truth.sigma, m.dynamics.sigma, s.truth.soft_vertices);
      print_moving_and_still(model, s, m);
      if (o.diagnose) print_diagnosis(model, s, m);
      std::cout << fmt::format("| {} | {} | {:g} | {:g} | {} | {} | {:.3f} | {:.3f} | {:+.1f} | {:.3f} | {:.1f} |\n",
                               c.motion, join(c.regions), c.amplitude_mm, c.frequency, beta_given ? "given" : "fitted",
                               validate::weighting_name(weighting), 1e3 * truth, 1e3 * recovered, error, r, seconds)
                << std::flush;
      results.push_back({{"motion", c.motion},
                         {"regions", join(c.regions)},
                         {"amplitude_mm", c.amplitude_mm},
                         {"frequency_hz", c.frequency},
                         {"frames", o.frames},
                         {"beta", beta_given ? "given" : "fitted"},
                         {"fit", validate::weighting_name(weighting)},
                         {"true_mean_sigma_mm", 1e3 * truth},
                         {"recovered_mean_sigma_mm", 1e3 * recovered},
                         {"error_percent", error},
                         {"correlation", r},
                         {"unconverged_frames", m.fit.unconverged_frames},
                         {"seconds", seconds}});
    }
}

/// Every case: the Markdown table and the JSON.
void run_benchmark(const MetricOptions& o) {
  const body::BodyModel model =
      body::load_body(o.body_path.empty() ? body::default_body_path() : std::filesystem::path(o.body_path));
  const std::vector<Case> cases = make_cases(o);
  nlohmann::json results = nlohmann::json::array();
  std::cout << "| motion | region | A [mm] | f [Hz] | β | fit | true σ̄ [mm] | recovered [mm] | error [%] | "
               "correlation | seconds |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Case& c : cases) measure_case(model, c, o, results);
  write_json(o.out, {{"benchmark", "metric"}, {"frames", o.frames}, {"results", results}});
  std::cout << "wrote " << o.out << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  MetricOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  try {
    run_benchmark(o);
  } catch (const std::exception& e) {
    std::cerr << "bench_metric: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
