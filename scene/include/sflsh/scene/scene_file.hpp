#pragma once
// Scene files (TOML, docs/scenes.md, examples in data/scenes/): bodies, rigid objects, the effects the scene
// calls for, time stepping and output. The simulator builds only what the effects ask for (scene_runner.hpp).
// Every error names the file and line: unknown keys, missing keys, wrong types, impossible values.
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_series.hpp>
#include <sflsh/model/layer_settings.hpp>
#include <sflsh/model/mass.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/run/run_defaults.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::scene {

/// What a scene asks to simulate. Anything not switched on is not built.
struct Effects {
  bool inertia = false;  ///< dynamics (backward Euler); off: quasi-static equilibrium per frame
  bool gravity = false;  ///< g = 9.81 m/s² · gravity_direction on the soft tissue (and on free objects)
  /// World direction of gravity (unit). [0, 0, −1]: the bodies lie on their backs, held by their skeletons.
  Eigen::Vector3d gravity_direction = -Eigen::Vector3d::UnitY();
  bool object_contact = false;  ///< rigid objects against the soft layers
  bool body_contact = false;    ///< bodies against each other
  /// Whether any effect deforms the tissue (otherwise every body is only skinned).
  bool elastic() const { return inertia || gravity || object_contact || body_contact; }
};

enum class SolverKind { full, reduced, skinned };
const char* solver_name(SolverKind kind);

/// A rigid placement in the world: p_world = R_y(yaw) p + position (Y up).
struct Placement {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< [m]
  double yaw_degrees = 0.0;                            ///< about +Y
};

/// A keyframe of a prescribed position (and, for objects, orientation).
struct SceneKeyframe {
  double t = 0.0;                                      ///< [s]
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  ///< axis-angle [degrees] (objects only)
};

/// The largest `motion_offset` (and crowd `max_offset`) accepted [s]: an hour, longer than any recorded
/// motion; procedural motions are periodic or settle well within it.
inline constexpr double kMaxMotionOffset = 3600.0;

/// The longest `duration` accepted [s] (a day; at most 10000 fps that is < 2³¹ frames). Runs far shorter
/// than this are still refused without --allow-long when their work estimate is too large (scene_runner.hpp).
inline constexpr double kMaxSceneDuration = 86400.0;

struct BodySpec {
  std::string name;
  int line = 0;                              ///< of its [[body]] table
  std::string body_path;                     ///< SMPL-layout .npz; empty: the open body
  std::string subject;                       ///< a subject name (data/subjects.toml) …
  std::optional<std::vector<double>> betas;  ///< … or β (up to 10 values)
  std::string motion = "rest";               ///< procedural name, an AMASS .npz, or "rest" (the rest pose, still)
  double motion_offset = 0.0;                ///< [s] the body's motion starts this far into the motion
  /// Root translation keyframes [m] added to the motion's (the body's own frame): a body walking into
  /// another. Empty: none.
  std::vector<SceneKeyframe> approach;
  Placement placement;
  SolverKind solver = SolverKind::reduced;
  // Unset keys take the body run's defaults (run/run_defaults.hpp, docs/body_run.md), as `sflsh simulate` does.
  std::string mesh{run::kDefaultMesh};  ///< coarse | default | fine
  std::string material;                 ///< material file; empty: the defaults at control_points
  int control_points = model::kDefaultControlPoints;
  int handles = run::kDefaultHandles;       ///< reduced: point handles
  int cubature = run::kDefaultCubature;     ///< reduced: −1 auto, 0 every tet
  double density = model::kDefaultDensity;  ///< [kg/m³]
  double stiffness_scale = 1.0;
  /// `integrator` (docs/integrators.md); a tracking skeleton without one takes the paper's backward Euler
  model::Integrator integrator = model::kDefaultIntegrator;
  model::MassKind mass = model::kDefaultMassKind;  ///< `mass`; lumped for a tracking skeleton without one
  /// `skeleton`: false ("prescribed") the bones follow the motion whatever touches them; true ("tracking", reduced
  /// only) the root's deviation from the motion is solved with the soft tissue (reduced/root_tracking.hpp).
  bool tracking = false;
  double tracking_stiffness = 600.0;  ///< [N/m] the root's translation; the rotation gets k ρ² (docs/scenes.md)
  double tracking_damping = 120.0;    ///< [N·s/m]; the rotation gets d ρ²
  bool free_root = false;             ///< `root = "free"`: no spring on the horizontal translation
  /// `tracked_joints`: the joints below the root that answer too ("all", the default, every joint carrying part of
  /// the layer; "root": none; or a list of joint names). Per joint a spring K_j = (2π joint_frequency)² I_j and a
  /// damper 2 joint_damping_ratio √(K_j I_j) (I_j: the moment of inertia of what it carries), overridden by name in
  /// joint_stiffness [N·m/rad] / joint_damping [N·m·s/rad]; a soft limit on the deviation at joint_limit [rad]
  /// (joint_limits by name).
  bool all_joints = true;
  std::vector<std::string> tracked_joints;  ///< when !all_joints: the names (empty: the root alone)
  double joint_frequency = 2.0;             ///< [Hz]
  double joint_damping_ratio = 0.7;
  double joint_limit = 0.5;  ///< [rad]
  std::map<std::string, double> joint_stiffness, joint_damping, joint_limits;
};

enum class ShapeKind { plane, sphere, box, capsule, mesh };
enum class ObjectMotionKind { fixed, prescribed, free };
const char* shape_name(ShapeKind kind);
const char* object_motion_name(ObjectMotionKind kind);

struct ObjectSpec {
  std::string name;
  int line = 0;
  ShapeKind shape = ShapeKind::sphere;
  double radius = 0.1;                                            ///< sphere, capsule [m]
  double length = 0.2;                                            ///< capsule: segment length along its local Z [m]
  Eigen::Vector3d half_extents = Eigen::Vector3d::Constant(0.1);  ///< box [m]
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();              ///< plane (world; through `position`)
  std::string mesh_path;                                          ///< mesh: a closed triangle mesh file
  double scale = 1.0;                                             ///< mesh: uniform scale of the file's coordinates
  Eigen::Vector3d position = Eigen::Vector3d::Zero();             ///< [m] world (the start for prescribed / free)
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();             ///< axis-angle [degrees]
  ObjectMotionKind motion = ObjectMotionKind::fixed;
  std::vector<SceneKeyframe> keyframes;                ///< prescribed: at least two, increasing t
  bool smooth = true;                                  ///< prescribed: C¹ (Catmull–Rom) instead of piecewise linear
  double mass = 1.0;                                   ///< free [kg] (used when density is 0)
  double density = 0.0;                                ///< free [kg/m³]; 0: the mass is given instead
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< free: initial [m/s]
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< free: initial, world [rad/s]
  double friction = 0.5;                                       ///< free: Coulomb coefficient μ
};

/// Penalty contact (docs/contact.md): all optional; zero / negative stiffness means the automatic one.
struct ContactSpec {
  double stiffness = 0.0;   ///< [N/m] per skin node; 0: automatic
  double tolerance = 1e-3;  ///< [m] deepest accepted penetration
  double margin = 1e-3;     ///< [m] the penalty acts within this distance outside the obstacle
  int max_refinements = 4;  ///< stiffenings per substep when the tolerance is exceeded
  /// Body against body: most solves of the touching bodies per step (each against the others' surfaces of the
  /// previous one) before the step is taken unconverged, with a warning.
  int max_exchanges = 30;
  /// true: the touching bodies exchange their end-of-step surfaces until they agree (the order of the bodies does
  /// not decide who deforms; the default); false: one Gauss–Seidel sweep per step in scene order (the body solved
  /// first takes most of the deformation), the former coupling, kept for comparison and speed.
  bool body_exchange = true;
  /// [m] the exchange has converged when no surface moved more than this from the surface it was solved against.
  double exchange_tolerance = 1e-4;
  /// Free objects and the body they touch: "monolithic" (default) solves the objects' six coordinates in the body's
  /// Newton solve where the scene allows it (one soft reduced body with a prescribed skeleton, docs/contact.md),
  /// else staggered; "staggered" always solves the objects first against the body's predicted skin.
  std::string object_coupling = "monolithic";
  /// Reduced bodies: local bumps where objects reach the skin (docs/contact.md "Local resolution of contact"), so the
  /// body dents where it is touched; false: the handles alone (the model before, stiffer and wider).
  bool local_resolution = true;
  double local_spacing = 0.0;  ///< [m] between the bumps' centres; 0: every node of the region is free (a patch)
  double local_depth = 0.04;   ///< [m] nodes up to this far (along the mesh) from the reached skin nodes
  double local_reach = 0.005;  ///< [m] a skin node is reached when an object comes this close to it (skinned)
  /// The largest patch [nodes]: its coordinates join the dense Newton solve (3 per node), so a larger one (a body
  /// lying on a floor) keeps the handles alone, with a warning.
  int local_max_nodes = 400;
  /// Also a patch where free objects land (off by default: a 2 kg ball sinks 17 cm into the full-space belly, deeper
  /// than a patch around its landing holds, and rolls off it; docs/contact.md).
  bool local_free_objects = false;
};

/// The paper's Fig. 1: `count` avatars with random shapes, each with its own shape-dependent material.
struct CrowdSpec {
  int line = 0;
  int count = 25;
  std::uint64_t seed = 1;
  double shape_sigma = 1.0;  ///< β ~ N(0, σ²) per component, clamped to ±3
  std::string motion = "dance";
  double max_offset = 2.0;  ///< [s] per-avatar time offsets uniform in [0, max_offset)
  double spacing = 1.0;     ///< [m] grid spacing
  int columns = 5;
  std::string shape_model;  ///< shape-model file; empty: data/shape_models/default.toml
  SolverKind solver = SolverKind::reduced;
  std::string mesh{run::kDefaultMesh};  ///< the body run's defaults (run/run_defaults.hpp), as a [[body]]
  int handles = run::kDefaultHandles;
  model::Integrator integrator = model::kDefaultIntegrator;  ///< `integrator`
  model::MassKind mass = model::kDefaultMassKind;            ///< `mass`
  int cubature = run::kDefaultCubature;
};

struct OutputSpec {
  bool layer = false;  ///< also the tet layers (<body>_layer.pvd)
  bool frames = true;  ///< the .pvd series (off: summary.json only)
  int every = 1;       ///< write every N-th frame (frame 0 and the last frame always)
  /// The arrays of the body (and layer) frames, names of model::frame_field_names(); nullopt: all.
  std::optional<std::vector<std::string>> fields;
  vtk::Compression compression = vtk::Compression::lz4;  ///< of the .vtp frame files: lz4 | zlib | none
  /// of the layers' .vtu frames: zlib (meshio reads no LZ4) unless `compression` is given, which sets both
  vtk::Compression layer_compression = vtk::Compression::zlib;
  /// "vtk": a .pvd of .vtp frames per body and object, and scene.pvd over all of them; "xdmf": <name>.xmf +
  /// <name>.h5 per body and for the objects (docs/output.md), no collection.
  std::string format = "vtk";
  /// of an xdmf series' datasets: zlib (shuffle + deflate) unless `compression` is given (none | zlib; HDF5 has no lz4)
  vtk::Compression series_compression = vtk::Compression::zlib;
  /// of an xdmf series' floating-point datasets: float64 | float32 (display); .vtp frames are Float64
  xdmf::Precision precision = xdmf::Precision::float64;
};

struct Scene {
  std::filesystem::path file;
  std::string name;
  double fps = 60.0;      ///< output frame rate
  int frames = 0;         ///< frames (0: from duration)
  double duration = 1.0;  ///< [s]
  int substeps = 1;       ///< solver steps per frame
  Effects effects;
  std::vector<BodySpec> bodies;
  std::vector<ObjectSpec> objects;
  ContactSpec contact;
  std::optional<CrowdSpec> crowd;
  OutputSpec output;

  /// Output frames including frame 0.
  int num_frames() const;
};

/// Reads and checks a scene file. Relative paths in it (body, motion, material, mesh, shape model) are taken
/// relative to the scene file's folder.
Scene load_scene(const std::filesystem::path& path);

}  // namespace sflsh::scene
