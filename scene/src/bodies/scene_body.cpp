// One body of a scene (scene_internal.hpp).
#include "bodies/body_skeleton.hpp"
#include "bodies/scene_internal.hpp"

#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/meshing/layer_cache.hpp>

#include <algorithm>
#include <chrono>

namespace sflsh::scene::detail {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

Rigid placement_transform(const Placement& placement) {
  Rigid r;
  r.R = Eigen::AngleAxisd(placement.yaw_degrees * EIGEN_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  r.t = placement.position;
  return r;
}

SceneBody::SceneBody(BodySpec spec, const body::BodyModel& model, const BodySetup& setup)
    : spec_(std::move(spec)), model_(model), placement_(placement_transform(spec_.placement)) {
  const auto t0 = Clock::now();
  const Scene& scene = *setup.scene;
  if (spec_.betas) {
    for (std::size_t k = 0; k < spec_.betas->size(); ++k) beta_[static_cast<Eigen::Index>(k)] = (*spec_.betas)[k];
    subject_label_ = "betas";
  } else if (!spec_.subject.empty()) {
    beta_ = body::find_subject(body::default_subjects(), spec_.subject).beta;
    subject_label_ = spec_.subject;
  } else {
    subject_label_ = "mean shape";
  }
  motion_ = scene_motion(spec_.motion, spec_.motion_offset, spec_.approach, scene.fps, scene.num_frames());
  solver_ = scene.effects.elastic() ? spec_.solver : SolverKind::skinned;
  vertex_node_.assign(static_cast<std::size_t>(model_.num_vertices()), -1);
  if (!soft()) {
    poser_ = std::make_unique<body::Poser>(model_, beta_);
    model_info = "skinned only (no layer built)";
    setup_seconds = seconds_since(t0);
    return;
  }
  std::optional<material::MaterialFile> material_file;
  if (!setup.material && !spec_.material.empty()) material_file = material::load_material_file(spec_.material);
  model::BodyLayerOptions options;
  options.mesher = meshing::Mesher::layered;
  options.size = meshing::parse_size_preset(spec_.mesh);
  if (!setup.cache_dir.empty()) options.cache_dir = setup.cache_dir;
  options.density = spec_.density;
  options.mass = spec_.mass;
  options.gravity = scene.effects.gravity;
  options.stiffness_scale = spec_.stiffness_scale;
  const material::MaterialFile* material = setup.material ? setup.material : material_file ? &*material_file : nullptr;
  layer_ = std::make_unique<model::BodyLayer>(
      model::build_body_layer(model_, beta_, motion_, material, spec_.control_points, options));
  const meshing::LayerMesh& mesh = *layer_->mesh;
  for (std::size_t r = 0; r < mesh.region_surface.vertices.size(); ++r)
    vertex_node_[static_cast<std::size_t>(mesh.region_surface.vertices[r])] = mesh.skin.node[r];
  if (solver_ == SolverKind::reduced) {
    reduced::ReducedModelOptions ro;
    ro.point_handles = spec_.handles;
    ro.cubature = spec_.cubature;
    if (!setup.cache_dir.empty()) ro.cache_dir = setup.cache_dir;
    reduced_model_ = reduced::build_reduced_model(*layer_, ro);
  }
  const model::Problem& problem = layer_->problem;
  model_info = fmt::format("{} nodes, {} tets", problem.num_nodes(), problem.num_tets());
  if (reduced_model_)
    model_info += fmt::format(", {} point handles, {} cubature tets", reduced_model_->handles.point_nodes.size(),
                              reduced_model_->cubature.size());
  setup_seconds = seconds_since(t0);
}

std::vector<int> SceneBody::contact_nodes() const {
  require(soft(), "scene body '{}': contact nodes of a skinned body", name());
  const model::Problem& problem = layer_->problem;
  const std::vector<char> constrained = problem.dirichlet.mask(problem.num_nodes());
  std::vector<int> nodes;
  for (int i : layer_->mesh->nodes_of_kind(meshing::NodeKind::outer)) {
    const auto d = static_cast<std::size_t>(3 * i);
    if (constrained[d] || constrained[d + 1] || constrained[d + 2]) continue;
    // The reduced model moves only nodes with basis functions (the others cannot respond).
    if (reduced_model_ && reduced_model_->subspace.basis.row(i).nonZeros() == 0) continue;
    nodes.push_back(i);
  }
  return nodes;
}

void SceneBody::set_local_region(std::vector<int> nodes, const reduced::LocalBasisOptions& options, int max_nodes) {
  require(solver_ == SolverKind::reduced, "scene body '{}': local bumps need the reduced solver", name());
  local_.reset();
  if (nodes.empty()) return;
  reduced::LocalBasis local = reduced::local_basis(layer_->problem, nodes, options);
  if (local.size() == 0) return;
  if (local.size() > max_nodes) {
    logger()->warn(
        "scene body '{}': a local patch of {} nodes (over local_max_nodes = {}) would make every Newton "
        "step a dense solve of {} coordinates; contact is resolved by the handles alone (docs/contact.md)",
        name(), local.size(), max_nodes, 3 * local.size());
    return;
  }
  const std::string what = local.spacing > 0.0
                               ? fmt::format("{} local bumps {:.0f} mm apart", local.size(), 1000.0 * local.spacing)
                               : fmt::format("{} free nodes", local.size());
  logger()->info("scene body '{}': {} over {} tets where objects reach {} skin nodes (local contact resolution)",
                 name(), what, local.tets.size(), nodes.size());
  reduced::ReducedModelOptions ro;
  ro.point_handles = spec_.handles;
  ro.cubature = spec_.cubature;
  local_cubature_ = reduced::cubature_outside(*layer_, reduced_model_->subspace, ro, local.tets);
  model_info += fmt::format(", {} over {} tets (cubature refitted without them: {} tets)", what, local.tets.size(),
                            local_cubature_.size());
  local_ = std::move(local);
}

void SceneBody::start(bool inertia) {
  quasi_static_ = !inertia;
  t_ = 0.0;
  if (!soft()) return;
  const model::Problem& problem = layer_->problem;
  run::SolverChoice choice;
  choice.kind = solver_ == SolverKind::reduced ? run::SolverKind::reduced : run::SolverKind::full;
  choice.integrator = spec_.integrator;
  choice.quasi_static = quasi_static_;
  if (solver_ == SolverKind::reduced) {
    choice.reduced.coupled = coupled_;
    choice.reduced.local = local_basis();
    if (spec_.tracking) {
      require(!quasi_static_, "scene body '{}': skeleton = \"tracking\" needs inertia ([effects] inertia = true)",
              name());
      reduced::RootTrackingOptions& root = choice.reduced.root;
      root.enabled = true;
      root.stiffness = spec_.tracking_stiffness;
      root.damping = spec_.tracking_damping;
      root.free_translation = spec_.free_root;
      // The pivot: the posed pelvis, M_0(t) (J_0, 1) with J_0 regressed from the shaped template.
      const Eigen::Vector3d pelvis = body::regress_joints(*layer_->model, layer_->shaped).row(0).transpose();
      root.pivot = [curve = layer_->curve, pelvis](double t) {
        model::JointTransforms m;
        curve->transforms(t, m);
        return Eigen::Vector3d(m[0].leftCols<3>() * pelvis + m[0].col(3));
      };
      root.joints = joint_tracking_options(spec_, *layer_);
    }
  }
  const run::ReducedParts parts =
      reduced_model_
          ? run::ReducedParts{&reduced_model_->subspace, local_ ? &local_cubature_ : &reduced_model_->cubature}
          : run::ReducedParts{};
  built_ = run::make_body_solver(problem, choice, model::initial_state(problem, 0.0), parts);
}

model::State SceneBody::state() const {
  require(soft(), "scene body '{}': a skinned body has no elastic state", name());
  if (!built_.reduced && !built_.full) return model::initial_state(layer_->problem, t_);  // before start()
  return built_.reduced ? built_.reduced->full_state() : built_.full->state();
}

Eigen::VectorXd SceneBody::positions() const {
  if (built_.reduced) return built_.reduced->positions();
  return state().x;
}

double SceneBody::max_elastic_displacement() const {
  if (!soft()) return 0.0;
  const RowMatrixX3d u = layer_->surface_displacement(positions());
  return u.rows() > 0 ? u.rowwise().norm().maxCoeff() : 0.0;
}

// Without inertia and gravity the only load is contact: when no potential finds a candidate for the step
// the equilibrium is the rest state, which needs no solve.
bool SceneBody::at_rest_this_step(double t0, double h) const {
  const model::Problem& problem = layer_->problem;
  if (!quasi_static_ || problem.gravity.squaredNorm() > 0.0 || coupled_) return false;
  if (problem.potentials.empty()) return true;
  const model::State s = state();
  Eigen::VectorXd rest_end = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
  problem.apply_dirichlet(t0 + h, rest_end);
  for (const auto& potential : problem.potentials) {
    const std::vector<int>& nodes = potential->nodes();
    model::NodeFrame start, end;
    if (problem.trajectory) {
      problem.trajectory->evaluate_nodes(t0, nodes, start);
      problem.trajectory->evaluate_nodes(t0 + h, nodes, end);
    }
    RowMatrixX3d p_start(static_cast<Eigen::Index>(nodes.size()), 3), p_end(static_cast<Eigen::Index>(nodes.size()), 3);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const Eigen::Vector3d x = s.x.segment<3>(3 * nodes[k]), X = rest_end.segment<3>(3 * nodes[k]);
      const auto row = static_cast<Eigen::Index>(k);
      if (problem.trajectory) {
        p_start.row(row) = (start.A[k] * x + start.d.row(row).transpose()).transpose();
        p_end.row(row) = (end.A[k] * X + end.d.row(row).transpose()).transpose();
      } else {
        p_start.row(row) = x.transpose();
        p_end.row(row) = X.transpose();
      }
    }
    if (potential->begin_substep(t0, h, p_start, p_end)) return false;
  }
  return true;
}

struct SceneBody::StepStart {
  double t = 0.0;
  long steps = 0, idle_steps = 0;
  std::optional<reduced::ReducedSolver::Checkpoint> reduced;
  std::optional<model::State> full;
};

void SceneBody::save_step_start() {
  auto s = std::make_shared<StepStart>();
  s->t = t_;
  s->steps = steps;
  s->idle_steps = idle_steps;
  if (built_.reduced) s->reduced = built_.reduced->checkpoint();
  if (built_.full) s->full = built_.full->state();
  start_ = std::move(s);
}

void SceneBody::restore_step_start() {
  require(start_ != nullptr, "scene body '{}': no step start saved", name());
  t_ = start_->t;
  steps = start_->steps;
  idle_steps = start_->idle_steps;
  if (built_.reduced) built_.reduced->restore(*start_->reduced);
  if (built_.full) built_.full->initialize(*start_->full);
}

void SceneBody::step(double t0, double h, EffectSeconds& seconds) {
  ++steps;
  if (!soft()) {
    t_ = t0 + h;
    return;
  }
  const auto clock = Clock::now();
  try {
    if (at_rest_this_step(t0, h)) {
      ++idle_steps;
      const model::State rest = model::initial_state(layer_->problem, t0 + h);
      if (built_.reduced)
        built_.reduced->initialize(rest);
      else
        built_.full->initialize(rest);
    } else if (built_.reduced) {
      const model::StepStats st = built_.reduced->step(h);
      newton_iterations += st.newton_iterations;
      refinements += st.potential_refinements;
      failed_attempts += st.failed_attempts;
      seconds.inertia += st.inertia_seconds;
      seconds.elasticity += st.seconds - st.inertia_seconds - st.potential_seconds;
    } else {
      const model::StepStats st = built_.full->step(h);
      newton_iterations += st.newton_iterations;
      refinements += st.potential_refinements;
      failed_attempts += st.failed_attempts;
      seconds.inertia += st.inertia_seconds;
      seconds.elasticity += st.seconds - st.inertia_seconds - st.potential_seconds;
    }
  } catch (const Error& e) {
    throw_error("body '{}': {}", name(), e.what());
  }
  t_ = t0 + h;
  solve_seconds += seconds_since(clock);
  if (tracking()) {
    // A step solved again (the body exchange restarts it from its start) replaces its row.
    const Eigen::VectorXd& deviation = built_.reduced->deviation();
    if (!deviation_history_.empty() && std::abs(deviation_history_.back().first - t_) < 1e-12)
      deviation_history_.back().second = deviation;
    else
      deviation_history_.emplace_back(t_, deviation);
  }
}

std::vector<reduced::Matrix34d> SceneBody::surface_deviation() const {
  if (!tracking()) return {};
  return surface_deviation_maps(*built_.reduced, *layer_);
}

std::vector<reduced::Matrix34d> SceneBody::node_deviation() const {
  if (!tracking()) return {};
  return node_deviation_maps(*built_.reduced, *layer_);
}

namespace {

/// The largest |r.segment<3>(c)| over the committed steps and its time [s].
std::pair<double, double> largest(const std::vector<std::pair<double, Eigen::VectorXd>>& history, Eigen::Index c) {
  std::pair<double, double> best{0.0, 0.0};
  for (const auto& [t, r] : history)
    if (r.segment<3>(c).norm() > best.first) best = {r.segment<3>(c).norm(), t};
  return best;
}

}  // namespace

// Over the steps as committed (deviation_history(): a step the body exchange solved again counts once).
nlohmann::json SceneBody::skeleton_summary() const {
  if (!tracking()) return {{"skeleton", "prescribed"}};
  const reduced::Vector6d r = built_.reduced->root();
  nlohmann::json joints = nlohmann::json::array();
  const reduced::SkeletonDeviation& skeleton = built_.reduced->skeleton();
  for (int j = 0; j < skeleton.num_joints(); ++j) {
    const auto sj = static_cast<std::size_t>(j);
    const Eigen::Index c = 6 + 3 * j;
    const auto [max_rotation, max_rotation_time] = largest(deviation_history_, c);
    joints.push_back({{"joint", body::kJointNames[static_cast<std::size_t>(skeleton.tracked()[sj])]},
                      {"stiffness_n_m_per_rad", built_.reduced->tracking_stiffness()[c]},
                      {"damping_n_m_s_per_rad", built_.reduced->tracking_damping()[c]},
                      {"limit_rad", built_.reduced->joint_limits()[j]},
                      {"moment_of_inertia_kg_m2", built_.reduced->joint_inertia()[j]},
                      {"max_rotation_rad", max_rotation},
                      {"max_rotation_time_s", max_rotation_time},
                      {"final_rotation_rad", built_.reduced->deviation().segment<3>(c).norm()}});
  }
  const auto [max_rotation, max_rotation_time] = largest(deviation_history_, 0);
  const auto [max_displacement, max_displacement_time] = largest(deviation_history_, 3);
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // τ at its largest (the body's frame) [m]
  for (const auto& [t, d] : deviation_history_)
    if (t == max_displacement_time) direction = d.segment<3>(3);
  return {{"skeleton", "tracking"},
          {"root", spec_.free_root ? "free" : "tracked"},
          {"tracking_stiffness_n_per_m", spec_.tracking_stiffness},
          {"tracking_damping_n_s_per_m", spec_.tracking_damping},
          {"root_stiffness",
           std::vector<double>(built_.reduced->root_stiffness().data(), built_.reduced->root_stiffness().data() + 6)},
          {"root_damping",
           std::vector<double>(built_.reduced->root_damping().data(), built_.reduced->root_damping().data() + 6)},
          {"root_coordinates_units", "rotation x, y, z [N·m/rad | N·m·s/rad], translation x, y, z [N/m | N·s/m]"},
          {"max_root_displacement_m", max_displacement},
          {"max_root_displacement_time_s", max_displacement_time},
          {"max_root_displacement_vector_m", {direction.x(), direction.y(), direction.z()}},
          {"max_root_rotation_rad", max_rotation},
          {"max_root_rotation_time_s", max_rotation_time},
          {"final_root_displacement_m", r.tail<3>().norm()},
          {"final_root_rotation_rad", r.head<3>().norm()},
          {"joint_frequency_hz", spec_.joint_frequency},
          {"joint_damping_ratio", spec_.joint_damping_ratio},
          {"joints", joints}};
}

// The skinned pose at time t, interpolated between the motion's frames (slerp per joint).
RowMatrixX3d SceneBody::skinned_world_surface(double t) const {
  const double f = t * motion_.fps;
  const auto last = static_cast<double>(motion_.num_frames() - 1);
  const auto k = static_cast<std::size_t>(std::clamp(std::floor(f + 1e-9), 0.0, last));
  const std::size_t k1 = std::min(k + 1, motion_.num_frames() - 1);
  const double u = std::clamp(f - static_cast<double>(k), 0.0, 1.0);
  const body::Pose theta = u < 1e-9 ? motion_.poses[k] : body::slerp_pose(motion_.poses[k], motion_.poses[k1], u);
  const Eigen::Vector3d trans = (1.0 - u) * motion_.trans[k] + u * motion_.trans[k1];
  return placement_.apply(poser_->pose(theta, trans) * motion_.world_from_body.transpose());
}

RowMatrixX3d SceneBody::world_surface() const {
  if (!soft()) return skinned_world_surface(t_);
  if (tracking()) return placement_.apply(apply_maps(surface_deviation(), layer_->posed_surface(positions(), t_)));
  return placement_.apply(layer_->posed_surface(positions(), t_));
}

// A tracking skeleton is carried at its current deviation.
RowMatrixX3d SceneBody::predicted_world_surface(double t) const {
  if (!soft()) return skinned_world_surface(t);
  if (tracking()) return placement_.apply(apply_maps(surface_deviation(), layer_->posed_surface(positions(), t)));
  return placement_.apply(layer_->posed_surface(positions(), t));
}

}  // namespace sflsh::scene::detail
