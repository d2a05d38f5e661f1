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
#include "fullspace_block.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>

namespace {

using namespace sflsh;

std::vector<std::string> split(const std::string& csv) {
  std::vector<std::string> out;
  std::stringstream stream(csv);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

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
  for (const std::string& c : split(block)) {
    std::array<int, 3> cells{};
    if (std::sscanf(c.c_str(), "%dx%dx%d", &cells[0], &cells[1], &cells[2]) != 3 || cells[0] < 1 || cells[1] < 1 ||
        cells[2] < 1) {
      std::cerr << "bench_fullspace: --block expects cells as NXxNYxNZ[,...], got " << c << "\n";
      return 2;
    }
    o.cells.push_back(cells);
  }
  for (const std::string& p : split(procs)) o.procs.push_back(std::stoi(p));
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

/// Reads the options (pairs of name and value); false after a message on an unknown one.
bool parse_arguments(int argc, char** argv, Arguments& a) {
  const std::map<std::string, std::function<void(const char*)>> setters = {
      {"--block", [&](const char* v) { a.block = v; }},
      {"--verify-args", [&](const char* v) { a.verify_args = v; }},
      {"--pcs", [&](const char* v) { a.pcs = v; }},
      {"--threads", [&](const char* v) { a.block_threads = std::stoi(v); }},
      {"--steps", [&](const char* v) { a.block_steps = std::stoi(v); }},
      {"--runs", [&](const char* v) { a.block_runs = std::stoi(v); }},
      {"--sflsh", [&](const char* v) { a.sflsh_path = v; }},
      {"--out", [&](const char* v) { a.out = v; }},
      {"--sizes", [&](const char* v) { a.sizes = v; }},
      {"--procs", [&](const char* v) { a.procs = v; }},
      {"--frames", [&](const char* v) { a.frames = std::stoi(v); }},
      {"--subject", [&](const char* v) { a.subject = v; }},
      {"--motion", [&](const char* v) { a.motion = v; }},
      {"--mesher", [&](const char* v) { a.mesher = v; }},
      {"--integrators", [&](const char* v) { a.integrators = v; }},
      {"--masses", [&](const char* v) { a.masses = v; }}};
  for (int i = 1; i + 1 < argc; i += 2) {
    const auto setter = setters.find(argv[i]);
    if (setter == setters.end()) {
      std::cerr << "bench_fullspace: unknown option " << argv[i] << "\n";
      return false;
    }
    setter->second(argv[i + 1]);
  }
  return true;
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
  for (const std::string& size : split(a.sizes))
    for (const std::string& p : split(a.procs))
      for (const std::string& integrator : split(a.integrators))
        for (const std::string& mass : split(a.masses)) {
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
                     {"integrators", split(a.integrators)},
                     {"masses", split(a.masses)},
                     {"results", results},
                     {"scaling_exponent", exponents}});
  std::cout << "wrote " << a.out << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (!parse_arguments(argc, argv, a)) return 2;
  try {
    if (!a.block.empty()) {
      bench::BlockOptions o;
      o.sflsh = a.sflsh_path;
      o.pcs = split(a.pcs);
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
