// Benchmark and recovery table of the dynamics metric (docs/validate.md "Recovery of known dynamics"): synthetic
// DYNA-layout sequences with known localized soft-tissue motion (synthetic_dyna.hpp) over procedural poses, the
// pose (and β) fit, σ by inverse skinning, against the known σ.
// Usage: bench_metric [--body PATH] [--frames N] [--table] [--out results.json]
//   default: the timing case (300 frames of running_on_spot, every region, 6 mm at 3 Hz), β given and fitted,
//            the rigidity fit and the earlier soft-weight fit;
//   --table: the recovery table over motions × regions × amplitude/frequency × β given/fitted, both fits.
// Prints a Markdown table and writes JSON (true and recovered mean σ over the soft region [mm], error [%],
// Pearson correlation of σ per soft-region vertex, seconds of fit + metric).
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
#include <cstring>
#include <iostream>
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

}  // namespace

int main(int argc, char** argv) {
  std::string body_path, out = "bench_metric.json";
  int frames = 300;
  bool table = false, only_rigidity = false, diagnose = false;
  Case single{"running_on_spot", validate::soft_motion_region_names(), 6.0, 3.0};  // --motion, --amplitude, --frequency
  validate::PoseFitOptions tuned;  // --rigid-depth, --temporal-weight, --min-weight, --stride
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--table") == 0)
      table = true;
    else if (std::strcmp(argv[i], "--rigidity-only") == 0)
      only_rigidity = true;
    else if (std::strcmp(argv[i], "--diagnose") == 0)
      diagnose = true;
    else if (i + 1 < argc && std::strcmp(argv[i], "--rigid-depth") == 0)
      tuned.rigid_depth = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--temporal-weight") == 0)
      tuned.temporal_weight = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--min-weight") == 0)
      tuned.min_weight = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--motion") == 0)
      single.motion = argv[++i];
    else if (i + 1 < argc && std::strcmp(argv[i], "--amplitude") == 0)
      single.amplitude_mm = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--frequency") == 0)
      single.frequency = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--region") == 0)
      single.regions = {argv[++i]};
    else if (i + 1 < argc && std::strcmp(argv[i], "--passes") == 0)
      tuned.reweighting_passes = std::stoi(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--min-motion-scale") == 0)
      tuned.min_motion_scale = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--min-reweight") == 0)
      tuned.min_reweight = std::stod(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--stride") == 0)
      tuned.vertex_stride = std::stoi(argv[++i]);
    else if (i + 1 < argc && std::strcmp(argv[i], "--body") == 0)
      body_path = argv[++i];
    else if (i + 1 < argc && std::strcmp(argv[i], "--out") == 0)
      out = argv[++i];
    else if (i + 1 < argc && std::strcmp(argv[i], "--frames") == 0)
      frames = std::stoi(argv[++i]);
  }
  try {
    const body::BodyModel model =
        body::load_body(body_path.empty() ? body::default_body_path() : std::filesystem::path(body_path));
    const std::vector<std::string> all = validate::soft_motion_region_names();
    std::vector<Case> cases;
    if (!table) {
      cases.push_back(single);
    } else {
      for (const std::string& motion : body::procedural_motion_names()) cases.push_back({motion, all, 6.0, 3.0});
      for (const std::string& region : all) cases.push_back({"running_on_spot", {region}, 6.0, 3.0});
      for (const auto& [a, f] : std::vector<std::pair<double, double>>{{2.0, 2.0}, {2.0, 6.0}, {8.0, 2.0}, {8.0, 6.0}})
        cases.push_back({"shake_hips", all, a, f});
    }
    nlohmann::json results = nlohmann::json::array();
    std::cout << "| motion | region | A [mm] | f [Hz] | β | fit | true σ̄ [mm] | recovered [mm] | error [%] | "
                 "correlation | seconds |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Case& c : cases) {
      validate::SyntheticSoftMotion spec;
      spec.motion = c.motion;
      spec.frames = frames;
      spec.regions = c.regions;
      spec.amplitude = 1e-3 * c.amplitude_mm;
      spec.frequency = c.frequency;
      const validate::SyntheticSoftSequence s = validate::synthetic_soft_motion(model, spec);
      const double truth = s.truth.mean_sigma_soft();
      for (const bool beta_given : {true, false})
        for (const validate::PoseFitWeighting weighting :
             {validate::PoseFitWeighting::soft_weight, validate::PoseFitWeighting::rigidity}) {
          if (only_rigidity && weighting != validate::PoseFitWeighting::rigidity) continue;
          validate::PoseFitOptions options = tuned;
          options.weighting = weighting;
          const auto t0 = std::chrono::steady_clock::now();
          const validate::RegistrationMetrics m = validate::registration_metrics(
              model, s.frames, spec.fps, beta_given ? std::optional<body::Betas>(s.beta) : std::nullopt, options);
          const double seconds = sflsh::seconds_since(t0);
          const double recovered = m.dynamics.mean_sigma_soft();
          const double error = 100.0 * (recovered - truth) / truth;
          const double r = validate::sigma_correlation(s.truth.sigma, m.dynamics.sigma, s.truth.soft_vertices);
          // Where the error sits (stderr): mean σ over the moving vertices and over the still soft vertices [mm].
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
          if (diagnose) print_diagnosis(model, s, m);
          std::cout << fmt::format(
                           "| {} | {} | {:g} | {:g} | {} | {} | {:.3f} | {:.3f} | {:+.1f} | {:.3f} | {:.1f} |\n",
                           c.motion, join(c.regions), c.amplitude_mm, c.frequency, beta_given ? "given" : "fitted",
                           validate::weighting_name(weighting), 1e3 * truth, 1e3 * recovered, error, r, seconds)
                    << std::flush;
          results.push_back({{"motion", c.motion},
                             {"regions", join(c.regions)},
                             {"amplitude_mm", c.amplitude_mm},
                             {"frequency_hz", c.frequency},
                             {"frames", frames},
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
    write_json(out, {{"benchmark", "metric"}, {"frames", frames}, {"results", results}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_metric: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
