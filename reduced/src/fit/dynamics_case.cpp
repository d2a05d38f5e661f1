#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/reduced/dynamics_case.hpp>
#include <sflsh/reduced/dynamics_sensitivity.hpp>
#include <sflsh/reduced/reduced_sensitivity.hpp>
#include <sflsh/reduced/young_map.hpp>
#include <sflsh/run/body_solver_factory.hpp>

#include <chrono>

namespace sflsh::reduced {

Eigen::VectorXd CaseDynamics::sigma() const {
  return (sigma_normal.array().square() + sigma_tangent.array().square()).sqrt().matrix();
}

double CaseDynamics::mean_sigma() const { return sigma_normal.size() ? sigma().mean() : 0.0; }

DynamicsCase::~DynamicsCase() = default;

DynamicsCase::DynamicsCase(const body::BodyModel& model, std::string subject, const body::Betas& beta,
                           const body::Motion& motion, const model::BodyLayerOptions& options)
    : subject_(std::move(subject)), motion_(motion.name), options_(options), fps_(motion.fps) {
  layer_ = std::make_unique<model::BodyLayer>(model::build_body_layer(model, beta, motion, nullptr, 1, options));
  frames_ = static_cast<int>(motion.num_frames());
  const meshing::RowMatrixX3d all = model::vertex_normals(layer_->shaped, model.faces);
  const std::vector<int>& region = layer_->mesh->region_surface.vertices;
  normals_.resize(static_cast<Eigen::Index>(region.size()), 3);
  for (std::size_t r = 0; r < region.size(); ++r) normals_.row(static_cast<Eigen::Index>(r)) = all.row(region[r]);
}

const SkinDisplacementMap& DynamicsCase::skin_map(const ReducedModel& model) const {
  std::call_once(skin_map_once_, [&] { skin_map_ = std::make_unique<SkinDisplacementMap>(*layer_, model.subspace); });
  return *skin_map_;
}

const meshing::ShapedLayer& DynamicsCase::shaped_layer(const LayerParameterization& parameterization) const {
  std::call_once(shaped_once_, [&] {
    shaped_ = std::make_unique<meshing::ShapedLayer>(parameterization.retargeter().shape(layer_->beta));
  });
  return *shaped_;
}

CaseDynamics DynamicsCase::simulate(const LayerParameterization& parameterization, const material::KappaMatrix& kappa,
                                    const ReducedModel& model, const ReducedOptions& options) const {
  const auto start = std::chrono::steady_clock::now();
  try {
    const model::Problem problem =
        parameterization.problem(*layer_, kappa, options_, nullptr, &shaped_layer(parameterization));
    const run::BuiltSolver built = run::make_body_solver(problem, run::reduced_choice(options),
                                                         model::initial_state(problem, 0.0), run::parts_of(model));
    const ReducedSolver& integrator = *built.reduced;
    const double setup_seconds = seconds_since(start);
    model::DynamicsAmplitude amplitude(normals_);
    // The attached nodes carry no elastic displacement (x_D = X), so u = (B ⊗ I₃) q; the skin embedding is
    // affine with weights summing to one, hence linear in u. No pass over the skinned trajectory per frame.
    require(problem.dirichlet.drives.empty(), "fit cases take fixed attachments only");
    const SkinDisplacementMap& skin = skin_map(model);
    auto add_frame = [&] { amplitude.add(skin.displacement_of(integrator.q())); };
    add_frame();
    model::FrameLoopOptions loop;
    loop.frames = frames_;
    loop.fps = fps_;
    model::run_frames(*built, loop, [&](int, double, const model::StepStats&) { add_frame(); });
    CaseDynamics out;
    out.sigma_normal = 1e3 * amplitude.sigma_normal();
    out.sigma_tangent = 1e3 * amplitude.sigma_tangent();
    require(out.sigma_normal.allFinite() && out.sigma_tangent.allFinite(), "non-finite dynamics amplitude");
    out.frames = frames_;
    out.cubature_added = integrator.cubature_added();
    out.setup_seconds = setup_seconds;
    out.seconds = seconds_since(start);
    return out;
  } catch (const Error& e) {
    throw Error(fmt::format("{} / {}: {}", subject_, motion_, e.what()));
  }
}

CaseDynamics DynamicsCase::simulate_with_sensitivity(const LayerParameterization& parameterization,
                                                     const material::KappaMatrix& kappa, const ReducedModel& model,
                                                     const Eigen::MatrixXd& young_map, Eigen::MatrixXd& dsigma,
                                                     const ReducedOptions& options, bool thickness) const {
  const auto start = std::chrono::steady_clock::now();
  try {
    int untangled = 0;
    const model::Problem problem =
        parameterization.problem(*layer_, kappa, options_, nullptr, &shaped_layer(parameterization), &untangled);
    require(problem.dirichlet.drives.empty(), "fit cases take fixed attachments only");
    if (thickness && untangled > 0)  // the exact columns assume nodes affine in h, which untangling breaks
      logger()->warn(
          "{} / {}: the retarget untangled {} nodes; the exact thickness columns are approximate here "
          "(--jacobian hybrid takes differences)",
          subject_, motion_, untangled);
    RestDirections rest;
    if (thickness) {  // dX/dh_i = (dX/dh) φ_i: the nodes are affine in h
      const meshing::ShapedLayer& shaped = shaped_layer(parameterization);
      for (int i = 0; i < parameterization.num_controls(); ++i)
        rest.directions.push_back(parameterization.retargeter().node_derivative(shaped, parameterization.phi().col(i)));
      rest.depth = parameterization.retargeter().depth();
    }
    // When the guard grows the cubature (a tet outside it leaves the material's range, reduced_solver.hpp), the
    // integrator takes the new tets' rows of the Young map and differentiates each substep on the cubature it was
    // solved with: the run simulate() makes, in one pass.
    const double setup_seconds = seconds_since(start);
    SensitivityIntegrator integrator(problem, model.subspace, model.cubature, young_map,
                                     sensitivity_solver_options(options), thickness ? &rest : nullptr);
    integrator.set_young_rows([&](const std::vector<int>& tets) {
      return young_tet_map(parameterization.retargeter(), parameterization.phi(), tets, options_.stiffness_scale);
    });
    integrator.initialize(model::initial_state(problem, 0.0));
    const int columns = static_cast<int>(integrator.dq_dyoung().cols());
    DynamicsAmplitudeSensitivity amplitude(normals_, columns);
    const SkinDisplacementMap& skin = skin_map(model);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dq;  // rows contiguous per function
    auto add_frame = [&] {
      dq = integrator.dq_dyoung();
      amplitude.add(skin.displacement_of(integrator.q()), skin.skin_basis(), dq);
    };
    add_frame();
    model::FrameLoopOptions loop;
    loop.frames = frames_;
    loop.fps = fps_;
    model::run_frames(integrator, loop, [&](int, double, const model::StepStats&) { add_frame(); });
    if (integrator.integrator().cubature_added() > 0)
      logger()->debug("{} / {}: the guard grew the cubature by {} tet(s) in the differentiated run", subject_, motion_,
                      integrator.integrator().cubature_added());
    CaseDynamics out;
    out.sigma_normal = 1e3 * amplitude.sigma_normal();
    out.sigma_tangent = 1e3 * amplitude.sigma_tangent();
    dsigma.resize(2 * out.sigma_normal.size(), columns);
    dsigma.topRows(out.sigma_normal.size()) = 1e3 * amplitude.sigma_normal_derivative();
    dsigma.bottomRows(out.sigma_normal.size()) = 1e3 * amplitude.sigma_tangent_derivative();
    require(out.sigma_normal.allFinite() && out.sigma_tangent.allFinite() && dsigma.allFinite(),
            "non-finite dynamics amplitude or derivative");
    out.frames = frames_;
    out.cubature_added = integrator.integrator().cubature_added();
    out.setup_seconds = setup_seconds;
    out.seconds = seconds_since(start);
    return out;
  } catch (const Error& e) {
    throw Error(fmt::format("{} / {}: {}", subject_, motion_, e.what()));
  }
}

}  // namespace sflsh::reduced
