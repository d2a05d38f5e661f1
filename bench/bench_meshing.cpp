// Benchmark: template layer meshing per backend and size preset, factorization and retargeting time,
// peak memory. Each configuration runs in a child process so its peak RSS is its own.
// Usage: bench_meshing [--body PATH] [--sizes coarse,default,fine] [--meshers cgal,gmsh] [--threads N]
//                      [--out bench_meshing.json]
#include "bench_options.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/meshing/retarget.hpp>

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>

namespace {

using namespace sflsh;

nlohmann::json run_one(const body::BodyModel& model, meshing::Mesher mesher, meshing::SizePreset size, int threads) {
  meshing::LayerMeshOptions options;
  options.mesher = mesher;
  options.size = size;
  options.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  const meshing::LayerMesh mesh = meshing::build_layer_mesh(model, options);
  const double mesh_s = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const meshing::Retargeter retargeter(model, mesh);
  const double factor_s = seconds_since(t1);
  const auto subjects = body::default_subjects();
  double retarget_s = 0.0, worst_dihedral = 180.0;
  int count = 0;
  for (const auto& subject : subjects) {
    const auto layer = retargeter.retarget(subject.beta, 0.5);
    retarget_s += layer.seconds;
    worst_dihedral = std::min(worst_dihedral, layer.quality.min_dihedral_deg);
    ++count;
  }
  const auto quality = meshing::quality_report(mesh.nodes, mesh.tets);
  return {{"mesher", meshing::mesher_name(mesher)},
          {"size", meshing::size_preset_name(size)},
          {"threads", threads},
          {"tets", mesh.num_tets()},
          {"nodes", mesh.num_nodes()},
          {"edge_length_m", mesh.edge_length},
          {"mesh_s", mesh_s},
          {"factorization_s", factor_s},
          {"retarget_mean_s", retarget_s / count},
          {"min_dihedral_deg", quality.min_dihedral_deg},
          {"median_dihedral_deg", quality.median_dihedral_deg},
          {"max_radius_edge", quality.max_radius_edge},
          {"retargeted_min_dihedral_deg", worst_dihedral}};
}

struct MeshingOptions {
  std::string body_path, out = "bench_meshing.json", sizes = "coarse,default,fine", meshers = "cgal,gmsh";
  int threads = 2;
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, MeshingOptions& o) {
  CLI::App app{
      "Template layer meshing per backend and size preset, factorization and retargeting time, peak "
      "memory; each configuration in a child process.",
      "bench_meshing"};
  bench::use_bench_defaults(app);
  app.add_option("--body", o.body_path, "Body model .npz in SMPL layout (default: the open body, data/open_body.npz)");
  app.add_option("--sizes", o.sizes, "Size presets, comma-separated: coarse | default | fine")
      ->check(bench::each_accepted_by("coarse|default|fine[,...]", meshing::parse_size_preset));
  app.add_option("--meshers", o.meshers, "Meshers, comma-separated: cgal | gmsh | layered")
      ->check(bench::each_accepted_by("cgal|gmsh|layered[,...]", meshing::parse_mesher));
  app.add_option("--threads", o.threads, "Threads of the mesher");
  app.add_option("--out", o.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

}  // namespace

int main(int argc, char** argv) {
  MeshingOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  const std::string &body_path = o.body_path, &out = o.out, &sizes = o.sizes, &meshers = o.meshers;
  const int threads = o.threads;
  try {
    sflsh::logger()->set_level(spdlog::level::warn);
    const body::BodyModel model =
        body::load_body(body_path.empty() ? body::default_body_path() : std::filesystem::path(body_path));
    nlohmann::json results = nlohmann::json::array();
    std::cout << fmt::format("{:<6} {:<8} {:>8} {:>8} {:>8} {:>9} {:>10} {:>9} {:>8} {:>8} {:>9}\n", "mesher", "size",
                             "tets", "nodes", "mesh s", "factor s", "retarget s", "min dih°", "med dih°", "max r/e",
                             "peak MB");
    for (const std::string& mesher_name : bench::split_list(meshers))
      for (const std::string& size_name : bench::split_list(sizes)) {
        const auto mesher = meshing::parse_mesher(mesher_name);
        const auto size = meshing::parse_size_preset(size_name);
        const auto result_file =
            std::filesystem::temp_directory_path() / fmt::format("bench_meshing_{}.json", ::getpid());
        std::cout.flush();  // the child inherits unflushed output otherwise
        const pid_t child = ::fork();
        if (child == 0) {
          int code = 0;
          try {
            write_json(result_file, run_one(model, mesher, size, threads));
          } catch (const std::exception& e) {
            std::cerr << "bench_meshing: " << mesher_name << " " << size_name << ": " << e.what() << "\n";
            code = 1;
          }
          std::cout.flush();
          ::_exit(code);
        }
        int status = 0;
        rusage usage{};
        ::wait4(child, &status, 0, &usage);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
          results.push_back({{"mesher", mesher_name}, {"size", size_name}, {"error", "failed (see stderr)"}});
          continue;
        }
        nlohmann::json r = read_json(result_file);
        std::filesystem::remove(result_file);
        r["peak_rss_mb"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
        std::cout << fmt::format(
            "{:<6} {:<8} {:>8} {:>8} {:>8.1f} {:>9.3f} {:>10.3f} {:>9.1f} {:>8.1f} {:>8.2f} {:>9.0f}\n", mesher_name,
            size_name, r["tets"].get<long>(), r["nodes"].get<long>(), r["mesh_s"].get<double>(),
            r["factorization_s"].get<double>(), r["retarget_mean_s"].get<double>(), r["min_dihedral_deg"].get<double>(),
            r["median_dihedral_deg"].get<double>(), r["max_radius_edge"].get<double>(), r["peak_rss_mb"].get<double>());
        results.push_back(r);
      }
    write_json(out, {{"benchmark", "meshing"}, {"body", model.name}, {"threads", threads}, {"results", results}});
    std::cout << "wrote " << out << "\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_meshing: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
