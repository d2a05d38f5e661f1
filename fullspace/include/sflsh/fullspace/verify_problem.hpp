#pragma once
// Verification problems (`sflsh verify`): a gmsh mesh, a homogeneous skin material, fixed and driven node
// groups and a time span, described in a TOML file, for comparing the full-space solver with other FEM
// codes. The keys are a user contract (docs of `sflsh verify`):
//
//   mesh = "layer.msh"               # .msh 2.2 or 4.1, relative to the TOML file's folder
//   density = 1000.0                 # kg/m³; 0 or absent = static
//   mass = "lumped"                  # "lumped" (ρV/4 per node, default) | "consistent" (needs density > 0)
//   gravity = [0.0, 0.0, -9.81]      # optional, m/s², default zero
//   [material]                       # young_tangent, young_normal [Pa] required; poisson (0.2), saturation (4),
//   normal = [0.0, 0.0, 1.0]         #   normal (z), fung_scale ("tangent_over_saturation" | "tangent_times_saturation"
//                                    #   | "none"), overflow ("throw" | "continue_linearly") optional
//   [[fix]]      group = "bone"  components = "xy"           # non-empty subset of "xyz"
//   [[drive]]    group = "bone"  component = "z"  expression = "0.01*sin(2*pi*2*t)"   # u(t) [m]
//   [time]       duration = 1.0  step = 0.001  rtol  atol
//                integrator = "backward_euler" | "bdf2" | "newmark" | "reference"   # bdf2/newmark/reference: dynamic
//                only
//   [record]     group = "top"  every = 16
//   [solver]     hessian = "projected" | "exact"             # optional
#include <sflsh/fullspace/model_names.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/material/psd_projection.hpp>
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::fullspace {

/// A verification problem as read from its TOML file (checked: groups exist, no dof both fixed and driven).
struct VerifyProblem {
  /// The full-space solver's integrators (model::Integrator) or the SUNDIALS reference.
  enum class Integrator { backward_euler, bdf2, newmark, reference };

  std::filesystem::path file;       ///< the TOML file
  std::filesystem::path mesh_path;  ///< the .msh file (resolved against the TOML file's folder)
  MshMesh mesh;
  double density = 0.0;                               ///< ρ [kg/m³]; 0 = static
  model::MassKind mass = model::MassKind::lumped;     ///< lumped or consistent inertia (mass.hpp)
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< g [m/s²]
  material::SkinMaterial material;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< through-thickness direction (unit)

  /// Components `mask` (bit 0 = x, 1 = y, 2 = z) of every node of `group` held at rest.
  struct Fix {
    std::string group;
    unsigned mask = 0;
  };
  std::vector<Fix> fixes;

  /// Component `axis` (0 = x, 1 = y, 2 = z) of every node of `group` displaced by u(t) = expression [m].
  struct Drive {
    std::string group;
    int axis = 0;
    std::string expression;  ///< muparser expression in t [s]; constants pi and e
  };
  std::vector<Drive> drives;

  double duration = 0.0;  ///< [s]
  double step = 0.0;      ///< [s]
  Integrator integrator = Integrator::backward_euler;
  double rtol = 1e-6;        ///< relative tolerance of the reference integrator
  double atol = 1e-9;        ///< absolute tolerance of the reference integrator [m, m/s]
  std::string record_group;  ///< the node group written to history.csv
  int record_every = 1;      ///< record every n-th step
  material::HessianProjection projection = material::HessianProjection::kStressDerivative;
};

/// Reads and checks a verification problem and its mesh. Throws sflsh::Error "<file>:<line>: key: what
/// was expected" for syntax errors, unknown keys, wrong types, missing or out-of-range values, unknown
/// groups (listing the mesh's groups), expressions muparser cannot evaluate at t = 0, a component
/// that is both fixed and driven (or driven twice), and consistent mass or an integrator other than
/// backward_euler on a static problem (density 0).
VerifyProblem load_verify_problem(const std::filesystem::path& path);

/// u(t) = expression (muparser, variable t, constants pi and e) and du/dt by central differences
/// (u(t+h) − u(t−h))/2h with h = 1e-6·max(1, |t|): truncation ~h²·u‴/6, round-off ~1e-16·|u|/h.
/// Copies share one parser (not thread-safe by itself), guarded by a mutex. Throws sflsh::Error naming the
/// expression when it does not parse or is not finite at t = 0, and naming it and t when a later value
/// is not finite.
ScalarDrive expression_drive(const std::string& expression);

/// The full-space problem: rest = mesh nodes, homogeneous make_orthotropic_fung(material, normal), lumped
/// masses ρV/4 (and mass_kind = spec.mass; validate() fills ρV per tet), gravity, projection, and the Dirichlet set of
/// the fixes and drives (one ScalarDrive per drive entry). No trajectory (p = x). Call Problem::validate() before
/// integrating.
Problem make_problem(const VerifyProblem& spec);

/// "backward_euler" | "bdf2" | "newmark" | "reference" (the spelling of the problem file).
std::string_view to_string(VerifyProblem::Integrator integrator);

/// The nodes of the record group, ascending.
std::vector<int> record_nodes(const VerifyProblem& spec);

}  // namespace sflsh::fullspace
