// Benchmark: the crowd scene of SFLSH Fig. 1 (data/scenes/crowd.toml: 25 avatars with random shapes, each its
// own shape-dependent material from the shipped shape model, dancing with per-avatar time offsets, reduced
// solver) run by the scene runner, parallel over bodies: frames per second of the whole crowd without writing
// on 1 and T threads and with writing every frame on T threads (into a scratch folder, removed afterwards),
// against the paper's 1.2 fps single-threaded, with the breakdown of a frame's wall time: stepping the
// bodies, posing the written surfaces, the rest of the output on the stepping thread (σ, queueing, waiting for
// the writer) and the overhead; the background writer's own busy time is listed beside it.
// Usage: bench_crowd [--scene data/scenes/crowd.toml] [--frames 60] [--threads 2] [--every 1] [--format vtk|xdmf]
//                    [--out bench_crowd.json]
#include "bench_options.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/xdmf_series.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <string>

namespace {

using namespace sflsh;

struct CrowdOptions {
  std::string scene_path = std::string(SFLSH_DATA_DIR) + "/scenes/crowd.toml", out = "bench_crowd.json";
  std::string format;  // empty: the scene's [output] format
  int frames = 60, threads = 2, every = 1;
};

/// Reads the command line into `o`; nothing to run, otherwise the exit status (bench_options.hpp).
std::optional<int> parse_options(int argc, char** argv, CrowdOptions& o) {
  CLI::App app{
      "The crowd scene of SFLSH Fig. 1 run by the scene runner: frames per second of the whole crowd "
      "without writing on 1 and T threads and with writing on T threads, with the breakdown of a frame.",
      "bench_crowd"};
  bench::use_bench_defaults(app);
  constexpr int kMaxInt = std::numeric_limits<int>::max();
  app.add_option("--scene", o.scene_path, "Scene file (TOML, docs/scenes.md)");
  app.add_option("--frames", o.frames, "Frames of the scene (the frames − 1 steps after the first are timed)")
      ->check(CLI::Range(2, kMaxInt, "at least 2"));
  app.add_option("--threads", o.threads, "Threads of the parallel runs (over bodies)")
      ->check(CLI::Range(1, kMaxInt, "at least 1"));
  app.add_option("--every", o.every, "Write every N-th frame in the writing run")
      ->check(CLI::Range(1, kMaxInt, "at least 1"));
  app.add_option("--format", o.format,
                 "Output of the writing run: vtk | xdmf, as sflsh simulate --format (default: the scene's [output] "
                 "format)")
      ->check(CLI::IsMember({"vtk", "xdmf"}));
  app.add_option("--out", o.out, "JSON file of the results");
  return bench::parse_command_line(app, argc, argv);
}

/// The scene with --format applied (as sflsh simulate --format: the scene's compression, lz4 refused for xdmf).
scene::Scene load_crowd_scene(const CrowdOptions& o) {
  scene::Scene scene = scene::load_scene(o.scene_path);
  if (!o.format.empty()) {
    model::check_output_format(o.format, "--format");
    scene.output.format = o.format;
    require(o.format != "xdmf" || scene.output.series_compression != vtk::Compression::lz4,
            "--format xdmf: the scene's compression lz4 is not available for HDF5 datasets");
  }
  return scene;
}

/// What the writing run writes, for the table's title and the JSON.
std::string written_output(const scene::Scene& scene) {
  const bool xdmf = scene.output.format == "xdmf";
  return xdmf ? fmt::format("xdmf series ({}, {})",
                            scene.output.precision == xdmf::Precision::float32 ? "Float32" : "Float64",
                            vtk::to_string(scene.output.series_compression))
              : fmt::format("vtk frame files (Float64, {})", vtk::to_string(scene.output.compression));
}

struct Run {
  int threads;
  bool write;
};

/// One run of the crowd: its row of the table (printed) and of the JSON.
nlohmann::json measure_run(const scene::Scene& scene, const CrowdOptions& o, const Run& r, const std::string& written,
                           const std::filesystem::path& scratch) {
  const int frames = o.frames, every = o.every;
  scene::SceneRunOptions options;
  options.frames = frames;
  options.threads = r.threads;
  options.write_frames = r.write;
  options.every = every;
  if (r.write) options.out = scratch;
  const nlohmann::json s = scene::run_scene(scene, options);
  if (r.write) std::filesystem::remove_all(scratch);
  const nlohmann::json& t = s["timings"];
  const double loop = t["loop_seconds"].get<double>(), fps = (frames - 1) / loop;
  const double step = t["step_seconds"].get<double>(), posing = t["posing_seconds"].get<double>();
  const double output = t["output_seconds"].get<double>() - posing;
  const double overhead = loop - step - t["output_seconds"].get<double>();
  const double writer = t.value("writer_seconds", 0.0);
  double solve = 0.0;  // summed over the bodies (CPU seconds on all threads)
  for (const auto& e : s["effects"])
    if (e["name"] != "skinning") solve += e["seconds"].get<double>();
  const auto avatars = s["bodies"].size();
  const double n = frames - 1;
  auto ms = [&](double seconds) { return 1e3 * seconds / n; };
  std::cout << fmt::format(
      "{:<8} {:<8} {:>8} {:>8.2f} {:>10.1f} | {:>9.1f} {:>9.1f} {:>9.1f} {:>9.1f} | {:>9.1f} {:>11.1f} {:>9.1f} "
      "{:>8.1f}×\n",
      r.threads, r.write ? "yes" : "no", avatars, fps, ms(loop), ms(step), ms(posing), ms(output), ms(overhead),
      ms(solve), ms(writer), t["setup_seconds"].get<double>(), fps / 1.2);
  return {{"threads", r.threads},
          {"writing", r.write},
          {"every", every},
          {"output", r.write ? written : std::string("none")},
          {"avatars", avatars},
          {"fps", fps},
          {"ms_per_frame", ms(loop)},
          {"step_ms", ms(step)},
          {"posing_ms", ms(posing)},
          {"output_ms", ms(output)},
          {"overhead_ms", ms(overhead)},
          {"solve_cpu_ms", ms(solve)},
          {"writer_busy_ms", ms(writer)},
          {"writer_wait_ms", ms(t.value("writer_wait_seconds", 0.0))},
          {"setup_seconds", t["setup_seconds"]},
          {"effects", s["effects"]},
          {"paper_fps_single_thread", 1.2}};
}

/// The runs on 1 and T threads without writing and on T threads with writing: the table and the JSON.
void run_benchmark(const CrowdOptions& o, const std::filesystem::path& scratch) {
  logger()->set_level(spdlog::level::warn);
  const scene::Scene scene = load_crowd_scene(o);
  const std::string written = written_output(scene);
  std::vector<Run> runs = {{1, false}, {o.threads, false}, {o.threads, true}};
  if (o.threads == 1) runs.erase(runs.begin());
  nlohmann::json rows = nlohmann::json::array();
  std::cout << fmt::format("crowd scene {}: {} frames at {} fps; writing: every {} frame(s), {}\n\n", o.scene_path,
                           o.frames, scene.fps, o.every, written);
  std::cout << fmt::format("{:<8} {:<8} {:>8} {:>8} {:>10} | {:>9} {:>9} {:>9} {:>9} | {:>9} {:>11} {:>9} {:>9}\n",
                           "threads", "writing", "avatars", "fps", "ms/frame", "step", "posing", "output", "overhead",
                           "solve cpu", "writer busy", "setup [s]", "vs 1.2");
  for (const Run& r : runs) rows.push_back(measure_run(scene, o, r, written, scratch));
  std::cout << "\n(ms per crowd frame, wall: step = stepping all bodies, posing = posing the written surfaces, "
               "output = the rest of "
               "the output on the stepping thread (σ, queueing, waiting for the writer); solve cpu = the bodies' "
               "solves summed over "
               "threads; writer busy = the background writer's time, overlapping the others)\n";
  write_json(o.out, {{"benchmark", "crowd"},
                     {"scene", o.scene_path},
                     {"frames", o.frames},
                     {"rows", rows},
                     {"output", written},
                     {"goal_fps_without_writing", 120},
                     {"goal_fps_writing", 30}});
  std::cout << "wrote " << o.out << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CrowdOptions o;
  if (const std::optional<int> status = parse_options(argc, argv, o)) return *status;
  const std::filesystem::path scratch =
      std::filesystem::temp_directory_path() / fmt::format("bench_crowd_{}", getpid());
  try {
    run_benchmark(o, scratch);
  } catch (const std::exception& e) {
    std::filesystem::remove_all(scratch);
    std::cerr << "bench_crowd: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
