// Benchmark: seconds per 1/60 s step of the full-space solver on the coarse, default and fine layers with
// 1 and 2 MPI processes, per time integrator and mass kind; Newton and KSP iterations per step, peak memory,
// and the scaling exponent of the time per step in the tet count. Each configuration is one
// `sflsh simulate --solver full --no-output` run (under mpiexec for P > 1); its summary.json gives the timings
// (mean and median over the frames), wait4 the peak RSS.
// Usage: bench_fullspace [--sflsh PATH] [--sizes coarse,default,fine] [--procs 1,2] [--frames 20]
//                        [--integrators backward_euler,bdf2,newmark] [--masses lumped,consistent]
//                        [--subject NAME] [--motion NAME] [--mesher layered] [--out bench_fullspace.json]
// The driven block against FEBio (fullspace_block.hpp; docs/results/performance.md):
//        bench_fullspace --block 10x10x3,20x20x6,40x40x12,80x80x24 [--pcs icc,gamg,hypre,automatic]
//                        [--procs 1,2] [--threads 1] [--steps 6] [--runs 3] [--verify-args "PETSC OPTIONS"]
//                        [--out bench_fullspace_block.json]
#include "bench_options.hpp"
#include "fullspace_block.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>

namespace {

using namespace sflsh;

/// Least-squares slope of log(y) against log(x).
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const auto n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  const double den = n * sxx - sx * sx;
  return den > 0 ? (n * sxy - sx * sy) / den : 0.0;
}

/// The median of the per-frame solve times divided by the steps per frame [s per step].
double median_seconds_per_step(const nlohmann::json& summary) {
  std::vector<double> per_step;
  const double substeps = summary["solver"]["substeps"].get<double>();
  for (const auto& frame : summary["frames"])
    if (frame["frame"].get<int>() > 0) per_step.push_back(frame["seconds"].get<double>() / substeps);
  return bench::median_of(per_step);
}

/// --block: the driven block against FEBio (fullspace_block.hpp); returns the exit code.
int run_block_mode(bench::BlockOptions o, const std::string& block, const std::string& procs, std::string out) {
  for (const std::string& c : bench::split_list(block)) {
    std::array<int, 3> cells{};
    if (std::sscanf(c.c_str(), "%dx%dx%d", &cells[0], &cells[1], &cells[2]) != 3 || cells[0] < 1 || cells[1] < 1 ||
        cells[2] < 1) {
      std::cerr << "bench_fullspace: --block expects cells as NXxNYxNZ[,...], got " << c << "\n";
      return 2;
    }
    o.cells.push_back(cells);
  }
  o.procs = bench::split_ints(procs);
  o.scratch = std::filesystem::temp_directory_path() / fmt::format("bench_fullspace_block_{}", ::getpid());
  const nlohmann::json rows = bench::run_block_table(o);
  std::filesystem::remove_all(o.scratch);
  if (out == "bench_fullspace.json") out = "bench_fullspace_block.json";
  write_json(out, {{"benchmark", "fullspace_block"},
                   {"problem", "examples/verify/febio_block refined, Newmark, consistent mass, 1/60 s steps"},
                   {"steps", o.steps},
                   {"runs", o.runs},
                   {"threads_per_process", o.threads},
                   {"verify_args", o.verify_args},
                   {"seconds_per_step", "median over steps 2..N, then over runs [s]"},
                   {"results", rows}});
  std::cout << "wrote " << out << "\n";
  return 0;
}

struct Arguments {
  std::string sflsh_path = SFLSH_CLI, out = "bench_fullspace.json", sizes = "coarse,default,fine", procs = "1,2";
  std::string subject = "OPEN_TRAIN_1", motion = "running_on_spot", mesher = "layered";
  std::string integrators = "backward_euler", masses = "lumped";
  int frames = 20;
  std::string block, pcs = "icc,gamg", verify_args;
  int block_threads = 1, block_steps = 6, block_runs = 3;
};

/// Reads the command line into `a`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_arguments(int argc, char** argv, Arguments& a) {
  CLI::App app{
      "Seconds per 1/60 s step of the full-space solver on the body layer per size, process count, "
      "integrator and mass (`sflsh simulate --solver full --no-output` runs); with --block, the driven "
      "block against FEBio (`sflsh verify` runs).",
      "bench_fullspace"};
  bench::use_bench_defaults(app);
  app.add_option("--sflsh", a.sflsh_path, "The sflsh executable");
  app.add_option("--out", a.out,
                 "JSON file of the results (with --block, the default becomes bench_fullspace_block.json)");
  app.add_option("--procs", a.procs, "MPI process counts, comma-separated (mpiexec -n P for P > 1)")
      ->check(bench::int_list());
  app.add_option("--sizes", a.sizes, "Layer resolutions, comma-separated: coarse | default | fine");
  app.add_option("--frames", a.frames, "Steps of 1/60 s per run (sflsh simulate --frames N+1)");
  app.add_option("--subject", a.subject, "Named subject (data/open_body_subjects.toml)");
  app.add_option("--motion", a.motion, "Procedural motion (sflsh motion list)");
  app.add_option("--mesher", a.mesher, "Layer mesher: layered | cgal | gmsh");
  app.add_option("--integrators", a.integrators, "Time integrators, comma-separated: backward_euler | bdf2 | newmark");
  app.add_option("--masses", a.masses, "Mass kinds, comma-separated: lumped | consistent");
  app.add_option("--block", a.block,
                 "The driven block against FEBio instead: refinements as cells NXxNYxNZ, comma-separated "
                 "(e.g. 10x10x3,20x20x6)");
  app.add_option("--pcs", a.pcs, "--block: preconditioners (sflsh verify --preconditioner), comma-separated");
  app.add_option("--threads", a.block_threads,
                 "--block: assembly threads per process (1: strong scaling counts cores; 0: the cores divided among "
                 "the processes)");
  app.add_option("--steps", a.block_steps, "--block: steps of 1/60 s per run (the first is not counted)");
  app.add_option("--runs", a.block_runs, "--block: runs of each configuration; the median is reported");
  app.add_option("--verify-args", a.verify_args,
                 "--block: PETSc options appended to every sflsh verify, in one argument (e.g. "
                 "\"-snes_lag_preconditioner 1\")");
  return bench::parse_command_line(app, argc, argv);
}

struct LayerRun {
  std::string size, integrator, mass;
  int np = 1;
};

/// One `sflsh simulate --solver full` run of the body layer: its row of the table (printed) and of the JSON.
nlohmann::json measure_layer_run(const Arguments& a, const LayerRun& run, const std::filesystem::path& scratch) {
  const auto& [size, integrator, mass, np] = run;
  const auto dir = scratch / fmt::format("{}_{}_{}_{}", size, np, integrator, mass);
  std::string command = fmt::format(
      "{} simulate --solver full --mesh {} --mesher {} --subject {} --motion {} --frames {} --integrator {} "
      "--mass {} --no-output -q --out {}",
      a.sflsh_path, size, a.mesher, a.subject, a.motion, a.frames + 1, integrator, mass, dir.string());
  if (np > 1) {
    command = fmt::format(
        "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 mpiexec -n "
        "{} {}",
        np, command);
  }
  const auto [code, peak_mb] = bench::run_measured(command);
  if (code != 0) {
    std::cerr << "bench_fullspace: " << size << " with " << np << " processes, " << integrator << ", " << mass
              << " mass failed (exit " << code << ")\n";
    return {{"size", size},
            {"procs", np},
            {"integrator", integrator},
            {"mass", mass},
            {"error", fmt::format("exit code {}", code)}};
  }
  const nlohmann::json summary = read_json(dir / "summary.json");
  const double steps =
      static_cast<double>(summary["motion"]["frames"].get<long>() - 1) * summary["solver"]["substeps"].get<double>();
  const double solve_s = summary["timings"]["solve_seconds"].get<double>();
  const double per_step = solve_s / steps;
  const double median = median_seconds_per_step(summary);
  const double newton = summary["solver"]["newton_iterations"].get<double>() / steps;
  const double ksp = summary["solver"]["linear_iterations"].get<double>() / steps;
  const double assembly =
      summary["timings"]["jacobian_seconds"].get<double>() + summary["timings"]["function_seconds"].get<double>();
  const long tets = summary["mesh"]["tets"].get<long>();
  nlohmann::json r = {{"size", size},
                      {"procs", np},
                      {"integrator", integrator},
                      {"mass", mass},
                      {"mesher", a.mesher},
                      {"tets", tets},
                      {"nodes", summary["mesh"]["nodes"]},
                      {"steps", steps},
                      {"seconds_per_step", per_step},
                      {"median_seconds_per_step", median},
                      {"newton_per_step", newton},
                      {"ksp_per_step", ksp},
                      {"assembly_fraction", solve_s > 0 ? assembly / solve_s : 0.0},
                      {"build_seconds", summary["timings"]["build_seconds"]},
                      {"peak_rss_mb", peak_mb}};
  std::cout << fmt::format(
      "{:<8} {:>5} {:<14} {:<10} {:>8} {:>8} {:>8.3f} {:>8.3f} {:>7.2f} {:>8.1f} {:>7.0f} {:>7.1f} {:>7.0f}\n", size,
      np, integrator, mass, tets, summary["mesh"]["nodes"].get<long>(), per_step, median, newton, ksp,
      100.0 * r["assembly_fraction"].get<double>(), r["build_seconds"].get<double>(), peak_mb);
  return r;
}

/// The body-layer table: every size × process count × integrator × mass, and the scaling exponent in the tet count.
int run_layer_mode(const Arguments& a) {
  nlohmann::json results = nlohmann::json::array();
  std::cout << fmt::format("{:<8} {:>5} {:<14} {:<10} {:>8} {:>8} {:>8} {:>8} {:>7} {:>8} {:>7} {:>7} {:>7}\n", "size",
                           "procs", "integrator", "mass", "tets", "nodes", "s/step", "median", "newton", "ksp/step",
                           "assem %", "build s", "peak MB");
  // (procs, integrator, mass) → (tets, s/step)
  std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> scaling;
  const auto scratch = std::filesystem::temp_directory_path() / fmt::format("bench_fullspace_{}", ::getpid());
  for (const std::string& size : bench::split_list(a.sizes))
    for (const std::string& p : bench::split_list(a.procs))
      for (const std::string& integrator : bench::split_list(a.integrators))
        for (const std::string& mass : bench::split_list(a.masses)) {
          const nlohmann::json r = measure_layer_run(a, {size, integrator, mass, std::stoi(p)}, scratch);
          results.push_back(r);
          if (r.contains("error")) continue;
          const std::string key = fmt::format("{} process(es), {}, {} mass", p, integrator, mass);
          scaling[key].first.push_back(r["tets"].get<double>());
          scaling[key].second.push_back(r["seconds_per_step"].get<double>());
        }
  std::filesystem::remove_all(scratch);
  nlohmann::json exponents = nlohmann::json::object();
  for (const auto& [key, data] : scaling) {
    if (data.first.size() < 2) continue;
    const double slope = loglog_slope(data.first, data.second);
    exponents[key] = slope;
    std::cout << fmt::format("scaling exponent (s/step ∝ tets^k) with {}: k = {:.2f}\n", key, slope);
  }
  write_json(a.out, {{"benchmark", "fullspace"},
                     {"subject", a.subject},
                     {"motion", a.motion},
                     {"frames", a.frames},
                     {"mesher", a.mesher},
                     {"integrators", bench::split_list(a.integrators)},
                     {"masses", bench::split_list(a.masses)},
                     {"results", results},
                     {"scaling_exponent", exponents}});
  std::cout << "wrote " << a.out << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (const std::optional<int> status = parse_arguments(argc, argv, a)) return *status;
  try {
    if (!a.block.empty()) {
      bench::BlockOptions o;
      o.sflsh = a.sflsh_path;
      o.pcs = bench::split_list(a.pcs);
      o.threads = a.block_threads;
      o.steps = a.block_steps;
      o.runs = a.block_runs;
      o.verify_args = a.verify_args;
      return run_block_mode(o, a.block, a.procs, a.out);
    }
    return run_layer_mode(a);
  } catch (const std::exception& e) {
    std::cerr << "bench_fullspace: error: " << e.what() << "\n";
    return 1;
  }
}
