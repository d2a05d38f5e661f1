#pragma once
// The driven flesh-layer block of the FEBio comparison (tests/data/febio/README.md): 10 × 10 × 3 cm, 10 × 10 × 3
// cells of 6 tets (1,800 tets, 484 nodes, the node order of FEBio's input), Y_t = 5 kPa, Y_n = 2 kPa, ν = 0.2,
// normal +z, ρ = 1000 kg/m³; the bottom face ("bone", box group zmin) held in x and y and driven in z by
// u(t) = 0.01 (1 − cos 4πt)² / 4 m; the top face (zmax, nodes 363–483) sampled every 1/60 s over 1 s.
// Written as a `sflsh verify` problem file and read through it, so the tests run what users run.
#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/fullspace/verify_problem.hpp>

#include <Eigen/Core>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace sflsh::testing {

/// The settings a block problem file varies.
struct BlockSettings {
  std::array<int, 3> cells = {10, 10, 3};
  std::string mass = "consistent";
  std::string integrator = "newmark";  ///< verify's [time] integrator (reference = SUNDIALS)
  std::string fung_scale = "tangent_over_saturation";
  double step = 1.0 / 960.0;  ///< [s]
  double duration = 1.0;      ///< [s]
  double rtol = 1e-9;         ///< the reference integrator's tolerances
  double atol = 1e-12;
};

/// u_z of the driven face at t [m]: 0.0025 (1 − cos 4πt)² (the FEBio input's load controller).
inline double block_drive(double t) {
  const double c = 1.0 - std::cos(4.0 * std::numbers::pi * t);
  return 0.0025 * c * c;
}

/// Writes block.msh and block.toml into `dir`; returns the problem file.
inline std::filesystem::path write_febio_block(const std::filesystem::path& dir, const BlockSettings& s) {
  const fullspace::MshMesh mesh = fullspace::box_tet_mesh(Eigen::Vector3d(0.1, 0.1, 0.03), s.cells);
  fullspace::write_msh(dir / "block.msh", mesh.nodes, mesh.tets, mesh.node_groups);
  const std::filesystem::path toml = dir / "block.toml";
  std::ofstream(toml) << fmt::format(R"(mesh = "block.msh"
density = 1000.0
mass = "{}"
[material]
young_tangent = 5000.0
young_normal = 2000.0
poisson = 0.2
saturation = 4.0
fung_scale = "{}"
normal = [0.0, 0.0, 1.0]
[[fix]]
group = "zmin"
components = "xy"
[[drive]]
group = "zmin"
component = "z"
expression = "0.0025*(1-cos(4*pi*t))^2"
[time]
duration = {:.17g}
step = {:.17g}
integrator = "{}"
rtol = {:.17g}
atol = {:.17g}
[record]
group = "zmax"
)",
                                     s.mass, s.fung_scale, s.duration, s.step, s.integrator, s.rtol, s.atol);
  return toml;
}

/// Displacements [m] of the top face's nodes (3 per node, ascending node number) at t = k / 60 s.
struct TopTrajectory {
  std::vector<int> nodes;
  std::vector<double> t;
  std::vector<Eigen::VectorXd> u;
  double seconds = 0.0;  ///< wall time of the run [s]
};

/// A FEBio node log as the README of tests/data/febio describes it (`t,node,ux,uy,uz`, 0-based nodes).
inline TopTrajectory read_febio_trajectory(const std::filesystem::path& path) {
  std::ifstream in(path);
  require(static_cast<bool>(in), "{}: cannot open", path.string());
  std::string line;
  std::getline(in, line);
  require(line == "t,node,ux,uy,uz", "{}: unexpected header '{}'", path.string(), line);
  std::map<long, std::map<int, Eigen::Vector3d>> samples;  // sample index → node → u
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream row(line);
    std::string field[5];
    for (std::string& f : field) std::getline(row, f, ',');
    const double t = std::stod(field[0]);
    samples[std::lround(60.0 * t)][std::stoi(field[1])] =
        Eigen::Vector3d(std::stod(field[2]), std::stod(field[3]), std::stod(field[4]));
  }
  TopTrajectory out;
  for (const auto& [k, nodes] : samples) {
    if (out.nodes.empty())
      for (const auto& entry : nodes) out.nodes.push_back(entry.first);
    require(nodes.size() == out.nodes.size(), "{}: sample {} has {} nodes, expected {}", path.string(), k, nodes.size(),
            out.nodes.size());
    Eigen::VectorXd u(3 * static_cast<Eigen::Index>(nodes.size()));
    Eigen::Index n = 0;
    for (const auto& entry : nodes) u.segment<3>(3 * n++) = entry.second;
    out.t.push_back(static_cast<double>(k) / 60.0);
    out.u.push_back(u);
  }
  return out;
}

inline std::filesystem::path febio_data(const std::string& name) {
  return std::filesystem::path(SFLSH_TEST_DATA_DIR) / "febio" / (name + ".csv");
}

/// max over samples and nodes of |u_a − u_b| [m] (samples present in both, matched by index).
inline double largest_difference(const TopTrajectory& a, const TopTrajectory& b) {
  require(a.nodes == b.nodes, "trajectories of different node sets");
  double out = 0.0;
  for (std::size_t k = 0; k < std::min(a.u.size(), b.u.size()); ++k) {
    for (Eigen::Index n = 0; n < a.u[k].size() / 3; ++n)
      out = std::max(out, (a.u[k].segment<3>(3 * n) - b.u[k].segment<3>(3 * n)).norm());
  }
  return out;
}

/// max over samples and nodes of the top face's motion relative to the driven bone, |u − (0, 0, u_bone(t))| [m].
inline double largest_motion(const TopTrajectory& a) {
  double out = 0.0;
  for (std::size_t k = 0; k < a.u.size(); ++k) {
    const Eigen::Vector3d bone(0.0, 0.0, block_drive(a.t[k]));
    for (Eigen::Index n = 0; n < a.u[k].size() / 3; ++n) out = std::max(out, (a.u[k].segment<3>(3 * n) - bone).norm());
  }
  return out;
}

/// |a − b| relative to the largest motion of `reference` (the comparisons' metric, tests/data/febio/README.md).
inline double relative_difference(const TopTrajectory& a, const TopTrajectory& b, const TopTrajectory& reference) {
  return largest_difference(a, b) / largest_motion(reference);
}

/// (4 fine − coarse) / 3: Richardson's extrapolation of two second-order runs with steps h and h/2.
inline TopTrajectory richardson(const TopTrajectory& coarse, const TopTrajectory& fine) {
  TopTrajectory out = fine;
  for (std::size_t k = 0; k < out.u.size(); ++k) out.u[k] = (4.0 * fine.u[k] - coarse.u[k]) / 3.0;
  return out;
}

/// A loaded block: its problem file, the verify problem and the validated full-space problem.
struct FebioBlock {
  fullspace::VerifyProblem spec;
  model::Problem problem;
  std::vector<int> top;
};

inline FebioBlock load_febio_block(const std::filesystem::path& dir, const BlockSettings& s) {
  FebioBlock b{fullspace::load_verify_problem(write_febio_block(dir, s)), {}, {}};
  b.problem = fullspace::make_problem(b.spec);
  b.problem.validate();
  b.top = fullspace::record_nodes(b.spec);
  return b;
}

/// Top-face displacements of a state vector x.
inline Eigen::VectorXd top_displacement(const FebioBlock& b, const Eigen::VectorXd& x) {
  Eigen::VectorXd u(3 * static_cast<Eigen::Index>(b.top.size()));
  for (std::size_t n = 0; n < b.top.size(); ++n)
    u.segment<3>(3 * static_cast<Eigen::Index>(n)) =
        x.segment<3>(3 * b.top[n]) - b.problem.rest.row(b.top[n]).transpose();
  return u;
}

/// Samples every `sample` seconds over the spec's duration; `advance(t)` returns x at t (t increasing).
template <typename Advance>
TopTrajectory sample_block(const FebioBlock& b, double sample, Advance&& advance) {
  const auto start = std::chrono::steady_clock::now();
  TopTrajectory out;
  out.nodes = b.top;
  const long samples = std::lround(b.spec.duration / sample);
  for (long k = 0; k <= samples; ++k) {
    const double t = static_cast<double>(k) * sample;
    out.t.push_back(t);
    out.u.push_back(top_displacement(b, k == 0 ? model::initial_state(b.problem, 0.0).x : advance(t)));
  }
  out.seconds = sflsh::seconds_since(start);
  return out;
}

/// The full-space solver (PETSc, this process) with the spec's integrator and step, sampled every `sample` s.
inline TopTrajectory run_fullspace(const FebioBlock& b, model::Integrator integrator, double sample = 1.0 / 60.0) {
  fullspace::FullSpaceOptions options;
  options.integrator = integrator;
  options.default_snes_rtol = 1e-10;  // well below the compared differences (Newton's own error ~1e-10 relative)
  options.default_snes_atol = 1e-13;
  options.default_ksp_rtol = 1e-10;
  fullspace::FullSpaceSolver solver(b.problem, MPI_COMM_SELF, options);
  model::State initial = model::initial_state(b.problem, 0.0);
  if (integrator == model::Integrator::newmark) initial.a = model::initial_acceleration(b.problem, initial);
  solver.initialize(initial);
  const double h = b.spec.step;
  const long per_sample = std::lround(sample / h);
  require(std::abs(static_cast<double>(per_sample) * h - sample) < 1e-12, "sample {} is not a multiple of {}", sample,
          h);
  return sample_block(b, sample, [&](double) {
    for (long k = 0; k < per_sample; ++k) solver.step(h);
    return solver.state().x;
  });
}

/// The SUNDIALS reference (ARKODE, order 5, the spec's rtol/atol), sampled every `sample` s.
inline TopTrajectory run_reference(const FebioBlock& b, double sample = 1.0 / 60.0) {
  fullspace::ReferenceOptions options;
  options.rtol = b.spec.rtol;
  options.atol = b.spec.atol;
  options.order = 5;
  fullspace::ReferenceIntegrator integrator(b.problem, options);
  integrator.initialize(model::initial_state(b.problem, 0.0));
  return sample_block(b, sample, [&](double t) { return integrator.advance_to(t).x; });
}

}  // namespace sflsh::testing
