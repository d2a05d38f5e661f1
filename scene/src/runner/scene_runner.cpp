// Running a scene (scene_runner.hpp): bodies, objects, contact on demand, stepping, output and summary.
#include "bodies/body_groups.hpp"
#include "bodies/crowd.hpp"
#include "bodies/group_step.hpp"
#include "bodies/scene_internal.hpp"
#include "contact/body_exchange.hpp"
#include "contact/local_region.hpp"
#include "contact/scene_contact.hpp"
#include "objects/free_objects.hpp"
#include "objects/object_coupling_setup.hpp"
#include "objects/scene_objects.hpp"
#include "runner/scene_output.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <limits>
#include <map>
#include <numeric>

namespace sflsh::scene {

namespace {

using detail::BodyContact;
using detail::BodyReach;
using detail::contact_fields;
using detail::contact_parameters;
using detail::deepest;
using detail::node_areas;
using detail::Rigid;
using detail::SceneBody;
using detail::SceneObject;
using meshing::RowMatrixX3d;
using Clock = std::chrono::steady_clock;

/// g [m/s²] in the world: 9.81 along the scene's gravity direction.
Eigen::Vector3d gravity_vector(const Effects& effects) { return 9.81 * effects.gravity_direction; }

class SceneRun {
 public:
  SceneRun(const Scene& scene, const SceneRunOptions& options) : scene_(scene), options_(options) {}

  nlohmann::json run() {
    const auto t_start = Clock::now();
    // Before anything is built or expanded: a mistyped duration or crowd count is refused with its estimate.
    check_work(
        estimate_scene_work(scene_, options_), WorkLimits{}, options_.allow_long,
        fmt::format("{}: [scene] duration × fps (or frames, --frames) × substeps × bodies{}", scene_.file.string(),
                    scene_.crowd ? fmt::format(" ([crowd] count at line {})", scene_.crowd->line) : ""));
    frames_ = options_.frames > 0 ? options_.frames : scene_.num_frames();
    Scene scene = scene_;
    scene.frames = frames_;
    build_bodies(scene);
    build_objects();
    build_contact();
    const double setup_seconds = seconds_since(t_start);
    for (auto& body : bodies_) body->start(scene_.effects.inertia);

    std::optional<RunFolder> run;
    if (!options_.out.empty() && options_.rank == 0) run.emplace(options_.out);
    RunFolder* folder = run && options_.write_frames && scene_.output.frames ? &*run : nullptr;
    every_ = options_.every > 0 ? options_.every : scene_.output.every;
    // Declared after the run folder: a failing run drops its pending writes before the folder is removed.
    std::optional<BackgroundJobs> jobs;
    // One writer thread: on 2 cores a second one only competed with the stepping threads (measured).
    if (folder && options_.background_writing) jobs.emplace(std::max<std::size_t>(8, 2 * bodies_.size() + 1));
    output_.emplace(scene_, bodies_, objects_, contact_, folder, jobs ? &*jobs : nullptr);
    write_frame(0);

    const double h = 1.0 / (scene_.fps * scene_.substeps);
    std::optional<tbb::global_control> threads;
    if (options_.threads > 0)
      threads.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(options_.threads));
    Progress progress("scene frames", frames_ - 1, options_.rank == 0);
    const auto t_loop = Clock::now();
    for (int f = 1; f < frames_; ++f) {
      const auto t_step = Clock::now();
      for (int k = 0; k < scene_.substeps; ++k) step(((f - 1) * scene_.substeps + k) * h, h);
      step_seconds_ += seconds_since(t_step);
      const auto t_out = Clock::now();
      write_frame(f);
      output_seconds_ += seconds_since(t_out);
      progress.advance();
    }
    const auto t_drain = Clock::now();
    if (jobs) jobs->wait();
    output_seconds_ += seconds_since(t_drain);
    progress.finish();
    const double loop_seconds = seconds_since(t_loop);
    output_->finish();
    const double total_seconds = seconds_since(t_start);
    nlohmann::json summary = make_summary(setup_seconds, loop_seconds, h);
    if (jobs) {
      summary["timings"]["writer_seconds"] = jobs->busy_seconds();
      summary["timings"]["writer_wait_seconds"] = jobs->waited_seconds();
    }
    if (run) {
      write_summary(*run, summary, total_seconds);
      run->commit();
    } else {  // no folder (no --out, or a rank other than 0): the returned summary has the run time all the same
      set_total_seconds(summary, total_seconds);
    }
    return summary;
  }

 private:
  // --- setup ---------------------------------------------------------------------------------------------
  const body::BodyModel& model_for(const std::string& path) {
    const std::string key = path.empty() ? body::default_body_path().string() : path;
    auto it = models_.find(key);
    if (it == models_.end()) {
      require(std::filesystem::exists(key), "{}: body model not found", key);
      it = models_.emplace(key, std::make_unique<body::BodyModel>(body::load_body(key))).first;
    }
    return *it->second;
  }

  void build_bodies(const Scene& scene) {
    std::vector<BodySpec> specs = scene.bodies;
    if (scene.crowd) {
      const body::BodyModel& model = model_for("");
      crowd_ = detail::expand_crowd(*scene.crowd, model, options_.data_dir);
      for (const BodySpec& b : crowd_.bodies) specs.push_back(b);
    }
    for (std::size_t i = 0; i < specs.size(); ++i) {
      detail::BodySetup setup;
      setup.scene = &scene;
      setup.cache_dir = options_.cache_dir;
      const std::size_t crowd_index = i - scene.bodies.size();
      if (i >= scene.bodies.size()) setup.material = &crowd_.materials[crowd_index];
      try {
        bodies_.push_back(std::make_unique<SceneBody>(specs[i], model_for(specs[i].body_path), setup));
      } catch (const Error& e) {
        throw_error("{}:{}: body '{}': {}", scene.file.string(), specs[i].line, specs[i].name, e.what());
      }
      // A tilted gravity acts on the tissue in the body's frame (placement: world = R p + t).
      if (bodies_.back()->soft() && scene.effects.gravity)
        bodies_.back()->layer().problem.gravity =
            bodies_.back()->placement().R.transpose() * gravity_vector(scene.effects);
      logger()->info("scene: body '{}' ({}): {}", specs[i].name, solver_name(bodies_.back()->solver()),
                     bodies_.back()->model_info);
    }
  }

  void build_objects() {
    for (const ObjectSpec& spec : scene_.objects) {
      try {
        objects_.push_back(detail::make_object(spec));
        if (spec.motion == ObjectMotionKind::free) detail::free_object_properties(spec);  // refused here, with its line
      } catch (const Error& e) {
        throw_error("{}:{}: object '{}': {}", scene_.file.string(), spec.line, spec.name, e.what());
      }
    }
    try {
      free_.emplace(objects_, scene_.contact,
                    scene_.effects.gravity ? gravity_vector(scene_.effects) : Eigen::Vector3d::Zero());
    } catch (const Error& e) {
      throw_error("{}: {}", scene_.file.string(), e.what());
    }
  }

  // Contact potentials exist only for the contact effects the scene asks for, and only on soft bodies.
  void build_contact() {
    contact_.resize(bodies_.size());
    if (!scene_.effects.object_contact && !scene_.effects.body_contact) return;
    const ContactParameters parameters = contact_parameters(scene_.contact);
    // Free objects in the body's own Newton solve where the scene allows it (object_coupling_setup.hpp).
    const bool monolithic = !free_->empty() && detail::monolithic_blocker(scene_, bodies_).empty();
    if (!free_->empty() && !monolithic)
      logger()->info("scene: free objects are solved before the bodies (staggered): {}",
                     detail::monolithic_blocker(scene_, bodies_));
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      SceneBody& body = *bodies_[b];
      if (!body.soft()) continue;
      BodyContact& c = contact_[b];
      const std::vector<int> nodes = body.contact_nodes();
      const std::vector<double> areas = node_areas(body, nodes);
      c.entry_of_node.assign(static_cast<std::size_t>(body.layer().problem.num_nodes()), -1);
      for (std::size_t k = 0; k < nodes.size(); ++k)
        c.entry_of_node[static_cast<std::size_t>(nodes[k])] = static_cast<int>(k);
      c.entry_of_vertex.assign(body.vertex_node().size(), -1);
      for (std::size_t v = 0; v < body.vertex_node().size(); ++v)
        if (const int node = body.vertex_node()[v]; node >= 0)
          c.entry_of_vertex[v] = c.entry_of_node[static_cast<std::size_t>(node)];
      const Rigid body_from_world = body.placement().inverse();
      if (scene_.effects.object_contact) {
        std::vector<ContactObstacle> obstacles;
        for (const SceneObject& o : objects_) {
          auto placed = std::make_shared<detail::PlacedMotion>(o.motion, body_from_world);
          c.placed.push_back(placed);
          // A coupled free object is in the body's solve through coupled_ instead.
          if (!monolithic || o.spec.motion != ObjectMotionKind::free)
            obstacles.push_back({detail::make_shape(o.spec), placed, fmt::format("object '{}'", o.spec.name)});
        }
        c.objects = std::make_shared<ContactPotential>(nodes, areas, std::move(obstacles), parameters);
        body.layer().problem.potentials.push_back(c.objects);
        if (body.solver() == SolverKind::reduced && scene_.contact.local_resolution)
          detail::add_local_patch(body, nodes, body_from_world, objects_, scene_.contact,
                                  std::max(frames_ - 1, 1) / scene_.fps,
                                  scene_.effects.gravity ? gravity_vector(scene_.effects) : Eigen::Vector3d::Zero());
        if (monolithic) {
          coupled_ = detail::make_coupled_objects(
              scene_, body, c, *free_, objects_,
              scene_.effects.gravity ? gravity_vector(scene_.effects) : Eigen::Vector3d::Zero());
          body.set_coupled(coupled_.get());
          c.coupled = coupled_.get();
          free_->set_coupled();
          logger()->info("scene: free objects are solved in body '{}''s Newton solve (monolithic)", body.name());
        } else if (!free_->empty()) {
          c.friction = std::make_shared<NodeLoads>(nodes);
          body.layer().problem.potentials.push_back(c.friction);
        }
      }
      if (scene_.effects.body_contact) {
        std::vector<ContactObstacle> obstacles;
        for (std::size_t o = 0; o < bodies_.size(); ++o) {
          if (o == b) continue;
          const body::BodyModel& model = bodies_[o]->model();
          auto mesh = std::make_shared<TriangleMesh>(body_from_world.apply(bodies_[o]->predicted_world_surface(0.0)),
                                                     model.faces);
          c.other.push_back(static_cast<int>(o));
          c.surfaces.push_back(mesh);
          obstacles.push_back({mesh, nullptr, fmt::format("body '{}'", bodies_[o]->name())});
        }
        c.bodies = std::make_shared<ContactPotential>(nodes, areas, std::move(obstacles), parameters);
        body.layer().problem.potentials.push_back(c.bodies);
      }
    }
  }

  // --- stepping ------------------------------------------------------------------------------------------
  // The bodies fall into groups that cannot touch each other in this step (every body its own group without
  // body contact). Within a group the touching bodies exchange their end-of-step surfaces until they agree
  // (step_group); groups of reduced and skinned bodies step in parallel (each integrator is single-threaded), and
  // so do the bodies within such a group; groups with a full-space body one after another (PETSc runs them on all
  // ranks). Free rigid objects take their implicit step first, against the bodies' skins predicted for the
  // step's end (free_objects.cpp); the bodies then feel them as obstacles where they now are.
  void step(double t0, double h) {
    const double t1 = t0 + h;
    if (!free_->empty() && !free_->coupled()) {
      free_->step(t0, h, detail::body_surfaces(bodies_, contact_, scene_.contact, t1, surface_cache_));
      apply_object_friction();
    }
    std::vector<RowMatrixX3d> predicted;
    std::vector<std::vector<std::size_t>> groups;
    if (scene_.effects.body_contact) {
      predicted.resize(bodies_.size());
      std::vector<BodyReach> reach(bodies_.size());
      tbb::parallel_for(std::size_t{0}, bodies_.size(), [&](std::size_t b) {
        if (bodies_[b]->solver() == SolverKind::full) return;  // PETSc objects: on the calling thread below
        reach[b] = body_reach(b, t1, predicted[b]);
      });
      for (std::size_t b = 0; b < bodies_.size(); ++b)
        if (bodies_[b]->solver() == SolverKind::full) reach[b] = body_reach(b, t1, predicted[b]);
      if (options_.group_bodies) {
        groups = contact_groups(reach, contact_reach());
      } else {
        groups.emplace_back(bodies_.size());
        std::iota(groups.back().begin(), groups.back().end(), std::size_t{0});
      }
    } else {
      for (std::size_t b = 0; b < bodies_.size(); ++b) groups.push_back({b});
    }
    std::vector<std::size_t> parallel, serial;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      bool full = false;
      for (std::size_t b : groups[g]) full = full || bodies_[b]->solver() == SolverKind::full;
      (full ? serial : parallel).push_back(g);
    }
    std::vector<detail::EffectSeconds> seconds(bodies_.size());
    std::vector<std::string> errors(groups.size());
    std::vector<std::vector<detail::ExchangeRecord>> records(groups.size());
    tbb::parallel_for(std::size_t{0}, parallel.size(), [&](std::size_t k) {
      const std::size_t g = parallel[k];
      try {
        detail::GroupStep(scene_, bodies_, contact_).run(groups[g], predicted, t0, h, seconds, records[g], true);
      } catch (const std::exception& e) {
        errors[g] = e.what();
      }
    });
    for (const std::string& e : errors)
      if (!e.empty()) throw_error("{}", e);
    for (std::size_t g : serial)
      detail::GroupStep(scene_, bodies_, contact_).run(groups[g], predicted, t0, h, seconds, records[g], false);
    for (const auto& s : seconds) add(s);
    for (auto& group_records : records)
      for (auto& r : group_records) exchanges_.push_back(std::move(r));
    ++steps_;
    groups_ += static_cast<long>(groups.size());
    if (coupled_) free_->account_coupled(coupled_->finish_step(), t1, coupled_->take_seconds());
    commit_objects(t1);
    for (std::size_t b = 0; b < bodies_.size(); ++b)
      if (bodies_[b]->soft()) detail::record_dent(*bodies_[b], contact_[b], t1);
  }

  /// The friction the free objects exerted on the bodies' skins in their step, as loads on the contact nodes
  /// under the skin vertices (in each body's frame) for the bodies' solves of the same step.
  void apply_object_friction() {
    const auto& on_bodies = free_->friction_on_bodies();
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      BodyContact& c = contact_[b];
      if (!c.friction) continue;
      c.friction->clear();
      const Eigen::Matrix3d body_from_world = bodies_[b]->placement().inverse().R;
      for (const auto& [vertex, force] : on_bodies[b])  // soft vertices only
        c.friction->add(c.entry_of_vertex[static_cast<std::size_t>(vertex)], body_from_world * force);
    }
  }

  /// The distance within which two bodies' reaches link them [m]: the potentials' margin and broad-phase
  /// safety plus 5 cm for the elastic motion of a step.
  double contact_reach() const {
    const ContactParameters p = contact_parameters(scene_.contact);
    return p.margin + p.broad_phase_safety + 0.05;
  }

  /// Body b's box over the step [t0, t1] (its surface now and predicted at t1, which is kept) and pad.
  BodyReach body_reach(std::size_t b, double t1, RowMatrixX3d& predicted) const {
    const SceneBody& body = *bodies_[b];
    const RowMatrixX3d now = body.world_surface();
    predicted = body.predicted_world_surface(t1);
    BodyReach r;
    double motion = 0.0;
    for (Eigen::Index v = 0; v < now.rows(); ++v) {
      r.box.extend(now.row(v).transpose());
      r.box.extend(predicted.row(v).transpose());
      motion = std::max(motion, (predicted.row(v) - now.row(v)).norm());
    }
    r.pad = motion + 2.0 * body.max_elastic_displacement();
    return r;
  }

  // Free objects: the reaction of every body, summed, moves the object once per step.
  void commit_objects(double t1) {
    for (std::size_t j = 0; j < objects_.size(); ++j) {
      SceneObject& o = objects_[j];
      if (o.motion->reacts()) {
        Eigen::Vector3d force = Eigen::Vector3d::Zero();
        double stiffness = 0.0;  // of the nodes touching it (makes the object's update implicit)
        for (BodyContact& c : contact_) {
          if (!c.objects) continue;
          force += c.placed[j]->take_force();
          for (Eigen::Index k = 0; k < c.objects->contact_force().rows(); ++k)
            if (c.objects->contact_force().row(k).squaredNorm() > 0.0)
              stiffness += c.objects->node_stiffness(static_cast<int>(k));
        }
        if (auto* free = dynamic_cast<FreeMotion*>(o.motion.get())) free->set_contact_stiffness(stiffness);
        o.motion->commit(t1, force);
      } else if (o.spec.motion == ObjectMotionKind::free && !coupled_) {
        Eigen::Vector3d force = Eigen::Vector3d::Zero();  // the bodies' reaction on the rigid object (summary)
        for (BodyContact& c : contact_)
          if (c.objects) force += c.placed[j]->take_force();
        free_->add_body_reaction(j, force);
      }
      o.world_shape->set_pose(o.motion->pose(t1));
    }
  }

  void add(const detail::EffectSeconds& s) {
    seconds_.elasticity += s.elasticity;
    seconds_.inertia += s.inertia;
  }

  // --- output --------------------------------------------------------------------------------------------
  // Independent check of the contact: the soft skin's deepest point inside any object or other body.
  void measure_penetration(double t) {
    std::vector<RowMatrixX3d> world(bodies_.size());
    std::vector<std::unique_ptr<TriangleMesh>> meshes(bodies_.size());
    for (std::size_t b = 0; b < bodies_.size(); ++b) world[b] = bodies_[b]->world_surface();
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      BodyContact& c = contact_[b];
      if (!c.objects && !c.bodies) continue;
      const std::vector<int>& region = bodies_[b]->layer().mesh->region_surface.vertices;
      RowMatrixX3d skin(static_cast<Eigen::Index>(region.size()), 3);
      for (std::size_t r = 0; r < region.size(); ++r) skin.row(static_cast<Eigen::Index>(r)) = world[b].row(region[r]);
      std::vector<const Obstacle*> shapes;
      if (c.objects)
        for (const SceneObject& o : objects_) shapes.push_back(o.world_shape.get());
      if (c.bodies) {
        for (int o : c.other) {
          auto& mesh = meshes[static_cast<std::size_t>(o)];
          if (!mesh)
            mesh = std::make_unique<TriangleMesh>(world[static_cast<std::size_t>(o)],
                                                  bodies_[static_cast<std::size_t>(o)]->model().faces);
          shapes.push_back(mesh.get());
        }
      }
      const double d = deepest(skin, shapes);
      if (d > c.max_penetration) {
        c.max_penetration = d;
        deepest_time_ = t;
      }
    }
  }

  // Frame f: σ of every soft body; when f is an output frame (every N-th, the first and the last) also the
  // independent penetration check and, with a run folder, the frame files (scene_output.hpp).
  void write_frame(int f) {
    const double t = f / scene_.fps;
    const bool output = model::is_written_frame(f, frames_, every_);
    if (output && (scene_.effects.object_contact || scene_.effects.body_contact)) {
      const auto clock = Clock::now();
      measure_penetration(t);
      check_seconds_ += seconds_since(clock);
    }
    if (output) free_->record(t);
    output_->frame(f, t, output);
  }

  // --- summary -------------------------------------------------------------------------------------------
  /// summary.json "effects": the effects that ran, with their time and share of the stepping loop.
  nlohmann::json effects_summary(double loop_seconds, bool solved, const detail::ContactTally& tally) const {
    const Effects& e = scene_.effects;
    nlohmann::json ran = nlohmann::json::array();
    auto entry = [&](const char* name, double seconds, const char* note) {
      nlohmann::json j = {
          {"name", name}, {"seconds", seconds}, {"share", loop_seconds > 0 ? seconds / loop_seconds : 0.0}};
      if (note && *note) j["note"] = note;
      ran.push_back(j);
    };
    entry("skinning", output_->skinning_seconds(),
          "posing the skinned bodies (soft bodies' skinning is inside their solves)");
    if (solved) {
      entry("elasticity", seconds_.elasticity, "the soft layers' solves without their mass and contact terms");
      if (e.inertia)
        entry("inertia", seconds_.inertia, e.gravity ? "the mass terms, gravity included" : "the mass terms");
      else if (e.gravity)
        entry("gravity", seconds_.inertia, "the mass terms of gravity");
      if (e.inertia && e.gravity) entry("gravity", 0.0, "inside the inertia terms");
    }
    if (e.object_contact && tally.potentials > 0)
      entry("object_contact", tally.object_seconds, "broad phase, penalty terms, acceptance");
    if (!free_->empty())
      entry("free_objects", free_->seconds(),
            free_->coupled() ? "the rigid objects' terms in the body's solve" : "the rigid objects' implicit solves");
    if (e.body_contact && tally.potentials > 0)
      entry("body_contact", tally.body_seconds, "other bodies' surfaces (trees), penalty terms");
    return ran;
  }

  /// summary.json's entry of body b (name, solver, subject, motion, placement, model, its steps and dynamics when
  /// soft, its contact), its contact counters added to `tally`.
  nlohmann::json body_summary(std::size_t b, detail::ContactTally& tally) const {
    const SceneBody& body = *bodies_[b];
    const BodyContact& c = contact_[b];
    nlohmann::json j = {{"name", body.name()},
                        {"solver_requested", solver_name(body.spec().solver)},
                        {"solver", solver_name(body.solver())},
                        {"subject", body.subject_label()},
                        {"beta", std::vector<double>(body.beta().data(), body.beta().data() + body.beta().size())},
                        {"motion", body.motion().name},
                        {"motion_offset", body.spec().motion_offset},
                        {"placement",
                         {{"position",
                           {body.spec().placement.position.x(), body.spec().placement.position.y(),
                            body.spec().placement.position.z()}},
                          {"yaw_degrees", body.spec().placement.yaw_degrees}}},
                        {"model", body.model_info},
                        {"setup_seconds", body.setup_seconds}};
    if (body.soft()) {
      j["integrator"] = std::string(model::to_string(body.spec().integrator));
      j["mass"] = std::string(model::to_string(body.spec().mass));
      j["steps"] = body.steps;
      j["idle_steps"] = body.idle_steps;
      j["newton_iterations"] = body.newton_iterations;
      j["failed_attempts"] = body.failed_attempts;
      j["contact_refinements"] = body.refinements;
      j["solve_seconds"] = body.solve_seconds;
      j["dynamics"] = output_->dynamics_summary(b);
      if (body.solver() == SolverKind::reduced) j["skeleton"] = body.skeleton_summary();
    }
    if (nlohmann::json contact = detail::contact_summary(c, tally); !contact.empty()) j["contact"] = contact;
    return j;
  }

  nlohmann::json make_summary(double setup_seconds, double loop_seconds, double h) const {
    nlohmann::json s = options_.header.is_object() ? options_.header : nlohmann::json::object();
    s["scene"] = {{"file", scene_.file.string()},
                  {"name", scene_.name},
                  {"fps", scene_.fps},
                  {"frames", frames_},
                  {"substeps", scene_.substeps},
                  {"step", h}};
    const Effects& e = scene_.effects;
    s["effects_requested"] = {{"inertia", e.inertia},
                              {"gravity", e.gravity},
                              {"object_contact", e.object_contact},
                              {"body_contact", e.body_contact},
                              {"self_contact", false}};
    long soft = 0, solved_steps = 0;
    detail::ContactTally tally;
    nlohmann::json bodies = nlohmann::json::array();
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
      const SceneBody& body = *bodies_[b];
      if (body.soft()) {
        ++soft;
        solved_steps += body.steps - body.idle_steps;
      }
      bodies.push_back(body_summary(b, tally));
    }
    s["bodies"] = bodies;
    nlohmann::json objects = nlohmann::json::array();
    for (const SceneObject& o : objects_) {
      const Eigen::Vector3d p = o.world_shape->pose().translation;
      objects.push_back({{"name", o.spec.name},
                         {"shape", shape_name(o.spec.shape)},
                         {"motion", object_motion_name(o.spec.motion)},
                         {"final_position", {p.x(), p.y(), p.z()}}});
    }
    s["objects"] = objects;
    if (!free_->empty()) s["free_objects"] = free_->summary();

    s["effects"] = effects_summary(loop_seconds, soft > 0 && solved_steps > 0, tally);
    s["built"] = {{"soft_layers", soft},
                  {"skinned_bodies", static_cast<long>(bodies_.size()) - soft},
                  {"contact_potentials", tally.potentials},
                  {"broad_phase_passes", tally.total.broad_phase_passes},
                  {"narrow_phase_evaluations", tally.total.narrow_phase_evaluations}};
    double measured = 0.0;
    for (const BodyContact& c : contact_) measured = std::max(measured, c.max_penetration);
    if (tally.potentials > 0)
      s["contact"] = {{"tolerance_mm", 1e3 * scene_.contact.tolerance},
                      {"max_penetration_mm", 1e3 * tally.total.max_penetration},
                      {"measured_max_penetration_mm", 1e3 * measured},
                      {"measured_at", deepest_time_},
                      {"skeleton_response",
                       std::any_of(bodies_.begin(), bodies_.end(), [](const auto& b) { return b->tracking(); })}};
    s["timings"] = {{"setup_seconds", setup_seconds},
                    {"loop_seconds", loop_seconds},
                    {"step_seconds", step_seconds_},
                    {"output_seconds", output_seconds_},
                    {"posing_seconds", output_->posing_seconds()},
                    {"penetration_check_seconds", check_seconds_},
                    {"frames_per_second", loop_seconds > 0 ? (frames_ - 1) / loop_seconds : 0.0}};
    s["output"] = {{"every", every_},
                   {"compression", vtk::to_string(scene_.output.compression)},
                   {"layer_compression", vtk::to_string(scene_.output.layer_compression)},
                   {"frames", scene_.output.frames},
                   {"format", scene_.output.format},
                   {"collections", output_->collections()}};
    if (scene_.output.fields) s["output"]["fields"] = *scene_.output.fields;
    if (e.body_contact)
      s["body_exchange"] =
          detail::exchange_summary(exchanges_, scene_.contact, [&](std::size_t b) { return bodies_[b]->name(); });
    if (e.body_contact)
      s["body_groups_per_step"] = steps_ > 0 ? static_cast<double>(groups_) / static_cast<double>(steps_) : 0.0;
    if (!crowd_.bodies.empty()) s["crowd"] = {{"avatars", crowd_.bodies.size()}, {"shape_model", crowd_.shape_model}};
    return s;
  }

  const Scene& scene_;
  const SceneRunOptions& options_;
  int frames_ = 0;
  std::map<std::string, std::unique_ptr<body::BodyModel>> models_;
  detail::Crowd crowd_;
  std::vector<std::unique_ptr<SceneBody>> bodies_;
  std::vector<SceneObject> objects_;
  std::optional<detail::FreeObjects> free_;          ///< the free rigid objects among objects_
  std::unique_ptr<detail::CoupledObjects> coupled_;  ///< them in the body's solve (null: staggered)
  detail::BodySurfaceCache surface_cache_;           ///< per body and vertex, for the free objects
  std::vector<BodyContact> contact_;
  std::optional<detail::SceneOutput> output_;  ///< the files of run() (its jobs are run()'s)
  int every_ = 1;
  detail::EffectSeconds seconds_;
  double output_seconds_ = 0.0, step_seconds_ = 0.0, check_seconds_ = 0.0, deepest_time_ = 0.0;
  long steps_ = 0, groups_ = 0;
  std::vector<detail::ExchangeRecord> exchanges_;  ///< per step and touching cluster, in step and group order
};

}  // namespace

nlohmann::json run_scene(const Scene& scene, const SceneRunOptions& options) { return SceneRun(scene, options).run(); }

}  // namespace sflsh::scene
