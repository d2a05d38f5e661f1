#pragma once
// bench_fullspace --block: the driven flesh-layer block of `sflsh verify` (examples/verify/febio_block, Newmark,
// consistent mass, Fung-orthotropic flesh, bone face driven in z) refined to the given cell counts, solved with
// each preconditioner on 1..P processes; seconds per 1/60 s step beside FEBio 4.11's on the same problem
// (docs/results/performance.md, "Against FEBio").
#include <sflsh/core/error.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/fullspace/msh_reader.hpp>

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace sflsh::bench {

struct BlockOptions {
  std::string sflsh;                      ///< the sflsh executable
  std::vector<std::array<int, 3>> cells;  ///< refinements (cells along x, y, z)
  std::vector<std::string> pcs;           ///< `sflsh verify --preconditioner` values
  std::vector<int> procs;
  int threads = 1;          ///< assembly threads per process (1: strong scaling counts cores)
  int steps = 6;            ///< steps of 1/60 s (the first carries the set-up and is not counted)
  int runs = 3;             ///< runs of each configuration; the median is reported
  std::string verify_args;  ///< appended to every `sflsh verify` (e.g. "-snes_lag_preconditioner 1")
  std::filesystem::path scratch;
};

/// FEBio 4.11 (BiCGStab, one process) on the same block, seconds per 1/60 s step: measured by the project on
/// this machine kind (docs/results/performance.md); zero where not measured.
inline double febio_seconds_per_step(long tets) {
  static const std::map<long, double> measured = {{1800, 0.032}, {14400, 0.289}, {115200, 2.67}};
  const auto it = measured.find(tets);
  return it == measured.end() ? 0.0 : it->second;
}

/// Runs a shell command and returns its exit status and the peak RSS of its largest descendant [MB].
inline std::pair<int, double> run_measured(const std::string& command) {
  std::cout.flush();
  const pid_t child = ::fork();
  if (child == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  rusage usage{};
  ::wait4(child, &status, 0, &usage);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, static_cast<double>(usage.ru_maxrss) / 1024.0};
}

inline double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Writes block.msh and block.toml for `cells` into `dir` (the febio_block example with 1/60 s steps).
inline void write_block_case(const std::filesystem::path& dir, std::array<int, 3> cells, int steps) {
  std::filesystem::create_directories(dir);
  const fullspace::MshMesh mesh = fullspace::box_tet_mesh(Eigen::Vector3d(0.1, 0.1, 0.03), cells);
  fullspace::write_msh(dir / "block.msh", mesh.nodes, mesh.tets, mesh.node_groups);
  std::ofstream toml(dir / "block.toml");
  toml << "mesh = \"block.msh\"\ndensity = 1000.0\nmass = \"consistent\"\n\n"
          "[material]\nyoung_tangent = 5000.0\nyoung_normal = 2000.0\npoisson = 0.2\nsaturation = 4.0\n"
          "fung_scale = \"tangent_over_saturation\"\nnormal = [0.0, 0.0, 1.0]\n\n"
          "[[fix]]\ngroup = \"zmin\"\ncomponents = \"xy\"\n\n"
          "[[drive]]\ngroup = \"zmin\"\ncomponent = \"z\"\nexpression = \"0.0025*(1-cos(4*pi*t))^2\"\n\n"
       << fmt::format("[time]\nduration = {:.17g}\nstep = {:.17g}\nintegrator = \"newmark\"\n\n", steps / 60.0,
                      1.0 / 60.0)
       << "[record]\ngroup = \"zmax\"\n";
  require(toml.good(), "bench_fullspace: cannot write {}", (dir / "block.toml").string());
}

/// One row of the table: a refinement, a preconditioner, a process count.
inline nlohmann::json run_block_row(const BlockOptions& o, const std::filesystem::path& case_dir, const std::string& pc,
                                    int np) {
  std::vector<double> per_step, peak;
  nlohmann::json summary;
  for (int run = 0; run < o.runs; ++run) {
    const auto out = case_dir / fmt::format("out_{}_{}_{}", pc, np, run);
    std::string command = fmt::format("{} -q verify {} --out {} --no-vtk --threads {}{}", o.sflsh,
                                      (case_dir / "block.toml").string(), out.string(), o.threads,
                                      " --preconditioner " + pc + (o.verify_args.empty() ? "" : " " + o.verify_args));
    if (np > 1) {
      command = fmt::format(
          "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 mpiexec -n {} "
          "{}",
          np, command);
    }
    const auto [code, peak_mb] = run_measured(command);
    if (code != 0) return {{"error", fmt::format("exit code {}", code)}};
    summary = read_json(out / "summary.json");
    std::vector<double> steps;
    for (std::size_t k = 1; k < summary["steps"].size(); ++k) steps.push_back(summary["steps"][k]["seconds"]);
    per_step.push_back(median_of(steps));
    peak.push_back(peak_mb);
    std::filesystem::remove_all(out);
  }
  const double newton = summary["solver"]["newton_iterations"].get<double>();
  const double steps = static_cast<double>(summary["steps"].size());
  return {{"seconds_per_step", median_of(per_step)},
          {"preconditioner_builds", summary["solver"]["preconditioner_builds"]},
          {"seconds_per_step_runs", per_step},
          {"newton_per_step", newton / steps},
          {"cg_per_newton", newton > 0 ? summary["solver"]["linear_iterations"].get<double>() / newton : 0.0},
          {"peak_rss_mb", median_of(peak)}};
}

/// The whole --block table; returns the JSON rows.
inline nlohmann::json run_block_table(const BlockOptions& o) {
  nlohmann::json rows = nlohmann::json::array();
  std::cout << fmt::format("{:>9} {:>8} {:<9} {:>5} {:>8} {:>9} {:>7} {:>9} {:>8} {:>8} {:>8}\n", "tets", "dofs", "pc",
                           "procs", "s/step", "speedup", "newton", "CG/newton", "peak MB", "FEBio s", "FEBio ×");
  for (const std::array<int, 3>& cells : o.cells) {
    const auto case_dir = o.scratch / fmt::format("block_{}x{}x{}", cells[0], cells[1], cells[2]);
    write_block_case(case_dir, cells, o.steps);
    const long tets = 6L * cells[0] * cells[1] * cells[2];
    const long dofs = 3L * (cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1);
    for (const std::string& pc : o.pcs) {
      double one_process = 0.0;
      for (int np : o.procs) {
        nlohmann::json r = run_block_row(o, case_dir, pc, np);
        r["cells"] = cells;
        r["tets"] = tets;
        r["dofs"] = dofs;
        r["pc"] = pc;
        r["procs"] = np;
        r["threads_per_process"] = o.threads;
        if (r.contains("error")) {
          std::cerr << fmt::format("bench_fullspace: block {} tets, {}, {} processes failed ({})\n", tets, pc, np,
                                   r["error"].get<std::string>());
          rows.push_back(r);
          continue;
        }
        const double s = r["seconds_per_step"];
        if (np == 1) one_process = s;
        const double speedup = one_process > 0.0 ? one_process / s : 0.0;
        const double febio = febio_seconds_per_step(tets);
        r["speedup_over_one_process"] = speedup;
        r["febio_seconds_per_step"] = febio;
        r["febio_over_sflsh"] = febio > 0.0 ? febio / s : 0.0;
        std::cout << fmt::format("{:>9} {:>8} {:<9} {:>5} {:>8.4f} {:>9.2f} {:>7.2f} {:>9.1f} {:>8.0f} {:>8} {:>8}\n",
                                 tets, dofs, pc, np, s, speedup, r["newton_per_step"].get<double>(),
                                 r["cg_per_newton"].get<double>(), r["peak_rss_mb"].get<double>(),
                                 febio > 0.0 ? fmt::format("{:.3f}", febio) : "–",
                                 febio > 0.0 ? fmt::format("{:.2f}", febio / s) : "–");
        rows.push_back(r);
      }
    }
    std::filesystem::remove_all(case_dir);
  }
  return rows;
}

}  // namespace sflsh::bench
