#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/run/body_solver_factory.hpp>
#include <sflsh/validate/ground_truth.hpp>
#include <sflsh/validate/true_material.hpp>

#include <chrono>

namespace sflsh::validate {

Eigen::VectorXd GroundTruthCase::sigma() const {
  Eigen::VectorXd s(sigma_normal.size() + sigma_tangent.size());
  s << sigma_normal, sigma_tangent;
  return s;
}

double GroundTruthCase::mean_sigma() const {
  return sigma_normal.size() ? (sigma_normal.array().square() + sigma_tangent.array().square()).sqrt().mean() : 0.0;
}

GroundTruthCase simulate_ground_truth(const model::BodyLayer& layer, const body::Motion& motion,
                                      const std::string& subject,
                                      const reduced::LayerParameterization& parameterization,
                                      const model::BodyLayerOptions& layer_options, const GroundTruthOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  GroundTruthCase out;
  out.subject = subject;
  out.motion = motion.name;
  out.beta = layer.beta;
  out.fps = motion.fps;
  out.kappa = options.truth.kappa_field(*layer.model, *layer.mesh, layer.beta, options.bounds);
  out.truth = options.truth.fingerprint();
  meshing::RowMatrixX3d rest_skin;
  const model::Problem problem = parameterization.problem_from_field(layer, out.kappa, layer_options, &rest_skin);
  run::SolverChoice choice;
  // The fit's synthetic truth keeps the paper's backward Euler (its reduced runs take theirs from the experiment's
  // ReducedOptions, also backward Euler); the masses are the layer options'.
  choice.integrator = model::Integrator::backward_euler;
  const run::BuiltSolver built =
      run::make_body_solver(problem, choice, model::initial_state(problem, 0.0), {}, MPI_COMM_SELF);
  const fullspace::FullSpaceSolver& solver = *built.full;
  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  const meshing::RowMatrixX3d all_normals = model::vertex_normals(layer.shaped, layer.model->faces);
  meshing::RowMatrixX3d normals(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r)
    normals.row(static_cast<Eigen::Index>(r)) = all_normals.row(region[r]);
  model::DynamicsAmplitude amplitude(normals);
  auto record = [&](double t) {
    const Eigen::Map<const meshing::RowMatrixX3d> nodes(solver.state().x.data(), problem.num_nodes(), 3);
    const meshing::RowMatrixX3d u = layer.mesh->skin_positions(nodes) - rest_skin;
    amplitude.add(u);
    if (options.keep_frames) out.posed.push_back(layer.posed_surface_from_displacement(u, t));
  };
  record(0.0);
  model::FrameLoopOptions loop;
  loop.frames = static_cast<int>(motion.num_frames());
  loop.fps = motion.fps;
  try {
    const model::StepStats total = model::run_frames(*built, loop, [&](int f, double, const model::StepStats&) {
      record(motion.time(static_cast<std::size_t>(f)));
    });
    out.newton_iterations += total.newton_iterations;
  } catch (const Error& e) {
    throw_error("ground truth {} / {}: {}", subject, motion.name, e.what());
  }
  out.sigma_normal = 1e3 * amplitude.sigma_normal();
  out.sigma_tangent = 1e3 * amplitude.sigma_tangent();
  require(out.sigma_normal.allFinite() && out.sigma_tangent.allFinite(), "ground truth {} / {}: non-finite dynamics",
          subject, motion.name);
  out.seconds = seconds_since(start);
  logger()->info("ground truth {} / {}: {} frames, mean σ {:.3f} mm, {:.1f} s", subject, motion.name, loop.frames,
                 out.mean_sigma(), out.seconds);
  return out;
}

void save_ground_truth_case(const std::filesystem::path& path, const GroundTruthCase& c) {
  std::vector<std::pair<std::string, npz::Array>> members;
  members.emplace_back("subject", npz::make_string(c.subject));
  members.emplace_back("motion", npz::make_string(c.motion));
  members.emplace_back("beta", npz::make_f64(Eigen::MatrixXd(c.beta.transpose())));
  members.emplace_back("fps", npz::make_scalar(c.fps));
  members.emplace_back("truth", npz::make_string(c.truth));
  members.emplace_back("sigma_normal", npz::make_f64(Eigen::MatrixXd(c.sigma_normal.transpose())));
  members.emplace_back("sigma_tangent", npz::make_f64(Eigen::MatrixXd(c.sigma_tangent.transpose())));
  members.emplace_back("kappa", npz::make_f64(Eigen::MatrixXd(c.kappa)));
  members.emplace_back("seconds", npz::make_scalar(c.seconds));
  if (!c.posed.empty()) {
    const auto V = static_cast<std::size_t>(c.posed.front().rows());
    std::vector<double> values;
    values.reserve(c.posed.size() * V * 3);
    for (const auto& frame : c.posed)
      for (Eigen::Index v = 0; v < frame.rows(); ++v)
        for (int k = 0; k < 3; ++k) values.push_back(frame(v, k));
    members.emplace_back("posed", npz::make_f64({c.posed.size(), V, 3}, values));
  }
  npz::write(path, members);
}

bool load_ground_truth_case(const std::filesystem::path& path, GroundTruthCase& c) {
  if (!std::filesystem::exists(path)) return false;
  try {
    const npz::Reader r(path);
    auto vec = [&](const std::string& key) {
      const std::vector<double> v = r.read(key).to_doubles();
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
    };
    c.subject = r.read("subject").to_string();
    c.motion = r.read("motion").to_string();
    c.beta = vec("beta");
    c.fps = vec("fps")[0];
    c.truth = r.has("truth") ? r.read("truth").to_string() : std::string("builtin normal-offset v1");
    c.sigma_normal = vec("sigma_normal");
    c.sigma_tangent = vec("sigma_tangent");
    const npz::Array k = r.read("kappa");
    const std::vector<double> kv = k.to_doubles();
    c.kappa = Eigen::Map<const material::KappaMatrix>(kv.data(), static_cast<Eigen::Index>(kv.size() / 3), 3);
    c.seconds = vec("seconds")[0];
    c.posed.clear();
    if (r.has("posed")) {
      const npz::Array p = r.read("posed");
      const std::vector<double> pv = p.to_doubles();
      const std::size_t T = p.shape.at(0), V = p.shape.at(1);
      for (std::size_t t = 0; t < T; ++t)
        c.posed.emplace_back(
            Eigen::Map<const body::RowMatrixX3d>(pv.data() + t * V * 3, static_cast<Eigen::Index>(V), 3));
    }
    return c.sigma_normal.size() == c.sigma_tangent.size() && c.sigma_normal.allFinite();
  } catch (const std::exception& e) {
    logger()->warn("ground truth cache {} unreadable ({}); recomputing", path.string(), e.what());
    return false;
  }
}

}  // namespace sflsh::validate
